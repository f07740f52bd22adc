"""Exact multivariate dynamic time warping between behaviours (SPEC §4).

Definition. For sequences x (n, D) and y (m, D) the local cost of aligning step i with
step j is the Euclidean distance c(i, j) = ||x_i - y_j||_2. The DTW distance is the
smallest sum of local costs along a warping path from (0, 0) to (n - 1, m - 1) with steps
(1, 0), (0, 1) and (1, 1):

    R(-1, -1) = 0,  R(i, -1) = R(-1, j) = inf,
    R(i, j) = c(i, j) + min(R(i - 1, j - 1), R(i - 1, j), R(i, j - 1)),
    dtw(x, y) = R(n - 1, m - 1).

No square root is taken of the total and there is no length normalisation. This is
dtaidistance's `dtw_ndim.distance(x, y, inner_dist="euclidean")`; its default
("squared euclidean": squared local costs, square root of the total) is a different
distance and is not what we compute.

Sakoe–Chiba window. `window = r` (an int >= 0, in steps) allows cell (i, j) only when

    -r - max(0, n - m) <= j - i <= r + max(0, m - n),

a band of radius r around both the diagonal from (0, 0) and the one ending at
(n - 1, m - 1), so a path exists for any lengths. With equal lengths this is |i - j| <= r
(r = 0: lock-step alignment). dtaidistance counts the diagonal itself as 1: our r is its
`window = r + 1`. `window=None` is unconstrained. A round's tree uses a band of radius
ceil(0.2 L) (`TreeConfig.dtw_band`, `band_window`): on 1.5 s Hopper behaviours it kept the
tree close to the unconstrained one (cophenetic r 0.96, level-1 ARI 0.94) in about half the
time, where a stride of 2 or a 10 % band changed a third of the level-1 groups
(`benchmarks/dtw_options.py`, docs/results/dtw-options).

Coarser time step. `stride = s` > 1 measures the DTW of block means: each sequence becomes
the means of s consecutive steps (a last, shorter block averages the steps left), and the
distance of those is multiplied by s, so it keeps the scale of the full-resolution distance
(a path over L / s coarse steps sums about L / s costs). A window is then ceil(r / s) coarse
steps. Only the distance is coarser: the clips and the reward model keep every step. The
work per pair falls by about s² (`benchmarks/dtw_options.py` measures how much that
changes the tree).

Speed. All N (N - 1) / 2 distances are computed by one numba kernel, parallel over rows
of the matrix (launched on about a tenth of the rows at a time, to report progress). The
local costs come from ||x||^2 + ||y||^2 - 2 x.y: the dot products are the only O(L^2 D)
work per pair and run as dense vectorised loops; every cost whose squared value is within
a relative `_EXACT_TOL` of cancellation is recomputed directly from the differences, so
identical steps cost exactly 0 and every cost keeps a relative error below about D * 1e-12.
The loops that turn products into costs run over slices indexed from 0 so that they are
vectorised, square roots included (indexed from the band's first column they compiled to
scalar code and took 60 % of a banded Hopper matrix; issue 22).
The dynamic programme runs on 8 pairs at once (one vector lane per pair: row a against 8
sequences of equal length). No O((N L)^2) matrix is ever held: memory is O(N L D). See
`benchmarks/dtw.py` for timings. The first call compiles the kernels (or loads them from
numba's on-disk cache); `warm_up` does that explicitly.

Processes. The kernel runs on numba's threading layer, OpenMP where available. numba
terminates a child forked from a process that has used the OpenMP layer, so a process
that computes distances should start its workers with "spawn" or "forkserver". Starting
that layer sets the OpenMP thread count of the whole process, torch's OpenMP runtime
included (a process that had asked torch for one thread found it on every core: two quick
GridWorld groupwise cells side by side on two cores took 108 s each instead of 27 s), so
every kernel launch restores the OpenMP limits it found (threadpoolctl).
"""

import contextlib
import math
import time
from collections.abc import Iterator, Sequence

import numba
import numpy as np
from numba import njit, prange
from threadpoolctl import threadpool_limits

from groupwise.types import FloatArray, IntArray, ProgressFn

_LANES = 8
"""Pairs per dynamic-programme step: one AVX-512 register, or two AVX2 registers, of float64."""
_EXACT_TOL = 1e-4
"""Squared costs below this fraction of ||x||^2 + ||y||^2 are recomputed from differences:
cancellation in the dot-product form loses log10(1 / (relative cost)) digits."""


def _as_sequences(sequences: Sequence[FloatArray]) -> list[np.ndarray]:
    out = []
    for i, s in enumerate(sequences):
        seq = np.ascontiguousarray(s, dtype=np.float64)
        if seq.ndim != 2 or seq.shape[0] == 0:
            raise ValueError(f"sequence {i}: expected a non-empty array (L, D), got {seq.shape}")
        if not np.isfinite(seq).all():
            raise ValueError(f"sequence {i} has non-finite values")
        out.append(seq)
    if len({s.shape[1] for s in out}) > 1:
        raise ValueError(f"sequences disagree on D: {sorted({s.shape[1] for s in out})}")
    return out


def _check_window(window: int | None) -> int:
    """The window as the kernels take it: -1 for none."""
    if window is None:
        return -1
    if int(window) != window or window < 0:
        raise ValueError(f"window must be None or an int >= 0, got {window!r}")
    return int(window)


def _check_stride(stride: int) -> int:
    if int(stride) != stride or stride < 1:
        raise ValueError(f"stride must be an int >= 1, got {stride!r}")
    return int(stride)


def coarsen(sequence: FloatArray, stride: int) -> FloatArray:
    """(ceil(L / stride), D) the means of `stride` consecutive steps of (L, D); the last
    block averages the steps left. stride 1 returns the steps unchanged."""
    seq = np.asarray(sequence, dtype=np.float64)
    stride = _check_stride(stride)
    if stride == 1:
        return seq
    starts = np.arange(0, seq.shape[0], stride)
    sums = np.add.reduceat(seq, starts, axis=0)
    counts = np.diff(np.append(starts, seq.shape[0]))
    return np.ascontiguousarray(sums / counts[:, None])


def band_window(band: float | None, length: int) -> int | None:
    """The Sakoe–Chiba radius ceil(band · length) steps of a band given as a share of the
    (longest) sequence length; None without a band."""
    if band is None:
        return None
    if not 0.0 < band <= 1.0:
        raise ValueError(f"band must be in (0, 1], got {band}")
    return math.ceil(band * length - 1e-9)


def _coarse_window(window: int, stride: int) -> int:
    return window if window < 0 else -(-window // stride)


def dtw_distance(x: FloatArray, y: FloatArray, window: int | None = None, stride: int = 1) -> float:
    """DTW distance (module docstring) between x (n, D) and y (m, D), with an optional
    Sakoe–Chiba `window` (steps) and a coarser time step `stride`."""
    a, b = _as_sequences([x, y])
    s = _check_stride(stride)
    w = _coarse_window(_check_window(window), s)
    return float(_pair_distance(coarsen(a, s), coarsen(b, s), w)) * s


def dtw_matrix(
    sequences: Sequence[FloatArray],
    window: int | None = None,
    progress: ProgressFn | None = None,
    stride: int = 1,
) -> FloatArray:
    """All pairwise DTW distances as a condensed vector.

    sequences: N arrays (L_i, D); lengths may differ. window: Sakoe–Chiba radius in steps
    (None: unconstrained); stride: the coarser time step (module docstring; 1: every step).
    Returns (N (N - 1) / 2,) float64 in `scipy.spatial.distance.squareform` order:
    entry N i - i (i + 1) / 2 + (j - i - 1) is dtw(sequences[i], sequences[j]) for i < j.
    N < 2 gives an empty vector. `progress` hears (pairs done, N (N - 1) / 2) after each
    launch of the kernel (`_rows_per_launch` rows of the matrix each: about ten a matrix).
    """
    s = _check_stride(stride)
    seqs = [coarsen(q, s) for q in _as_sequences(sequences)]
    w = _coarse_window(_check_window(window), s)
    n = len(seqs)
    out = np.zeros(n * (n - 1) // 2)
    if n < 2:
        return out
    lengths = np.array([s.shape[0] for s in seqs], dtype=np.int64)
    # sorted by length so that runs of equal length fill the vector lanes
    perm = np.argsort(lengths, kind="stable").astype(np.int64)  # sorted position -> input index
    ln = lengths[perm]
    offsets = np.zeros(n + 1, dtype=np.int64)
    offsets[1:] = np.cumsum(ln)
    steps = np.concatenate([seqs[i] for i in perm], axis=0)  # (sum L, D)
    sq = np.einsum("ij,ij->i", steps, steps)

    members, batch_len = _batches(ln)
    batch_col = np.zeros(len(batch_len) + 1, dtype=np.int64)
    batch_col[1:] = np.cumsum(batch_len * _LANES)
    # column j * LANES + k of a batch is step j of its k-th member: the lane layout
    cols = np.concatenate(
        [
            (offsets[members[b]][None, :] + np.arange(batch_len[b])[:, None]).ravel()
            for b in range(len(batch_len))
        ]
    )
    lane_steps_t = np.ascontiguousarray(steps[cols].T)  # (D, batches * L * LANES)
    lane_sq = np.ascontiguousarray(sq[cols])
    # the first batch holding a member after a: rows only compute pairs (a, b > a)
    first_batch = np.searchsorted(members[:, -1], np.arange(n), side="right").astype(np.int64)
    # row a computes its pairs with b > a: heavy and light rows alternate, so every chunk of
    # two rows is the same amount of work
    order = np.empty(n, dtype=np.int64)
    order[0::2] = np.arange((n + 1) // 2)
    order[1::2] = n - 1 - np.arange(n // 2)
    pairs_of_row = n - 1 - order  # row a computes its pairs with the b > a
    done, total = 0, n * (n - 1) // 2
    if progress is not None:
        progress(done, total)
    # small chunks handed out dynamically: a thread that loses its core to another process
    # does not hold up the whole matrix (static halves did, on a shared 2-core machine)
    with threadpool_limits(limits=None, user_api="openmp"), numba.parallel_chunksize(2):
        rows = _rows_per_launch(n)  # starts numba's threading layer: inside the limits
        for first in range(0, n, rows):
            _matrix_kernel(
                steps,
                sq,
                offsets,
                ln,
                order[first : first + rows],
                lane_steps_t,
                lane_sq,
                batch_col,
                batch_len,
                members,
                first_batch,
                w,
                perm,
                out,
            )
            done += int(pairs_of_row[first : first + rows].sum())
            if progress is not None:
                progress(done, total)
    if s > 1:
        out *= s
    return out


def _rows_per_launch(n: int) -> int:
    """Rows of the matrix one kernel launch computes: about a tenth of them, so progress is
    reported about ten times a matrix, but at least 2 per thread, so that every thread has a
    chunk (`parallel_chunksize(2)`); even, so heavy and light rows (`order`) pair up and
    every chunk is the same work."""
    rows = max(2 * numba.get_num_threads(), math.ceil(n / 10))
    return rows + rows % 2


def set_kernel_threads(n: int) -> int:
    """The kernels this thread launches from now on run on `n` threads (at most numba's
    NUMBA_NUM_THREADS, at least 1); returns the count before.

    A process that shares its cores with other work (the app's worker, whose PPO wants one
    thread) starts with NUMBA_NUM_THREADS = its cores, sets one thread here, and raises the
    count only around a distance matrix it computes while nothing else of its own runs
    (`kernel_threads` in `worker.jobs.prepare`).
    """
    with threadpool_limits(limits=None, user_api="openmp"):  # starting the layer resets it
        before = numba.get_num_threads()
        most = numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]  # set at numba's import
        numba.set_num_threads(max(1, min(n, most)))
    return before


@contextlib.contextmanager
def kernel_threads(n: int) -> Iterator[int]:
    """`set_kernel_threads(n)` within the block; yields the count set."""
    before = set_kernel_threads(n)
    try:
        yield numba.get_num_threads()
    finally:
        set_kernel_threads(before)


def warm_up() -> float:
    """Compile (or load from numba's cache) every kernel; returns the seconds it took."""
    start = time.perf_counter()
    rng = np.random.default_rng(0)
    seqs = [rng.normal(size=(length, 2)) for length in (3, 3, 4)]
    dtw_matrix(seqs)
    dtw_distance(seqs[0], seqs[2])
    return time.perf_counter() - start


def _batches(lengths: IntArray) -> tuple[IntArray, IntArray]:
    """Group sorted positions into batches of up to LANES consecutive equal-length sequences.

    Returns members (B, LANES), short batches padded by repeating their last member, and
    the length (B,) of each batch.
    """
    members = []
    batch_len = []
    n = len(lengths)
    i = 0
    while i < n:
        j = i
        while j < n and j - i < _LANES and lengths[j] == lengths[i]:
            j += 1
        members.append(list(range(i, j)) + [j - 1] * (_LANES - (j - i)))
        batch_len.append(lengths[i])
        i = j
    return np.array(members, dtype=np.int64), np.array(batch_len, dtype=np.int64)


@njit(cache=True, fastmath=True)
def _products_full(xa: np.ndarray, lane_t: np.ndarray, col: int, width: int, g: np.ndarray) -> None:
    """g[i, c] = xa[i] . lane_t[:, col + c] for i < len(xa), c < width: `_products` without
    a band (a separate kernel: the banded one's per-row ranges cost a third more here).

    Two rows and four dimensions per pass keep the vector loop's loads per FMA low.
    """
    na = xa.shape[0]
    dim = xa.shape[1]
    i = 0
    while i + 1 < na:
        r0 = g[i]
        r1 = g[i + 1]
        for c in range(width):
            r0[c] = 0.0
            r1[c] = 0.0
        d = 0
        while d + 4 <= dim:
            x0 = xa[i, d]
            x1 = xa[i, d + 1]
            x2 = xa[i, d + 2]
            x3 = xa[i, d + 3]
            z0 = xa[i + 1, d]
            z1 = xa[i + 1, d + 1]
            z2 = xa[i + 1, d + 2]
            z3 = xa[i + 1, d + 3]
            y0 = lane_t[d, col : col + width]
            y1 = lane_t[d + 1, col : col + width]
            y2 = lane_t[d + 2, col : col + width]
            y3 = lane_t[d + 3, col : col + width]
            for c in range(width):
                a = y0[c]
                b = y1[c]
                e = y2[c]
                f = y3[c]
                r0[c] += x0 * a + x1 * b + x2 * e + x3 * f
                r1[c] += z0 * a + z1 * b + z2 * e + z3 * f
            d += 4
        while d < dim:
            x0 = xa[i, d]
            z0 = xa[i + 1, d]
            y0 = lane_t[d, col : col + width]
            for c in range(width):
                r0[c] += x0 * y0[c]
                r1[c] += z0 * y0[c]
            d += 1
        i += 2
    if i < na:
        r0 = g[i]
        for c in range(width):
            r0[c] = 0.0
        for d in range(dim):
            x0 = xa[i, d]
            y0 = lane_t[d, col : col + width]
            for c in range(width):
                r0[c] += x0 * y0[c]


@njit(cache=True)
def _costs_full(
    xa: np.ndarray,
    sqa: np.ndarray,
    lane_t: np.ndarray,
    lane_sq: np.ndarray,
    col: int,
    width: int,
    g: np.ndarray,
) -> None:
    """Turn the dot products in g into Euclidean local costs, in place (no band)."""
    na = xa.shape[0]
    dim = xa.shape[1]
    other = lane_sq[col : col + width]
    for i in range(na):
        s = sqa[i]
        row = g[i, :width]
        small = 0
        for c in range(width):
            t = s + other[c]
            v = t - 2.0 * row[c]
            row[c] = v
            small += v <= _EXACT_TOL * t
        if small:
            for c in range(width):
                if row[c] <= _EXACT_TOL * (s + other[c]):
                    v = 0.0
                    for d in range(dim):
                        diff = xa[i, d] - lane_t[d, col + c]
                        v += diff * diff
                    row[c] = v
        for c in range(width):
            row[c] = np.sqrt(row[c])


@njit(cache=True, fastmath=True)
def _products(
    xa: np.ndarray,
    lane_t: np.ndarray,
    col: int,
    lo: np.ndarray,
    hi: np.ndarray,
    g: np.ndarray,
) -> None:
    """g[i, c] = xa[i] . lane_t[:, col + c] for i < len(xa) and c in [lo[i], hi[i]) lanes
    (times `_LANES`: the steps of the other sequences a band allows row i).

    Two rows and four dimensions per pass keep the vector loop's loads per FMA low; a pass
    covers the union of its two rows' ranges. Every value is summed in the same order
    whatever the ranges, so a band changes which cells are computed, never their values.
    """
    na = xa.shape[0]
    dim = xa.shape[1]
    i = 0
    while i + 1 < na:
        c0 = min(lo[i], lo[i + 1]) * _LANES
        c1 = max(hi[i], hi[i + 1]) * _LANES
        width = c1 - c0
        r0 = g[i, c0:c1]
        r1 = g[i + 1, c0:c1]
        for c in range(width):
            r0[c] = 0.0
            r1[c] = 0.0
        d = 0
        while d + 4 <= dim:
            x0 = xa[i, d]
            x1 = xa[i, d + 1]
            x2 = xa[i, d + 2]
            x3 = xa[i, d + 3]
            z0 = xa[i + 1, d]
            z1 = xa[i + 1, d + 1]
            z2 = xa[i + 1, d + 2]
            z3 = xa[i + 1, d + 3]
            y0 = lane_t[d, col + c0 : col + c1]
            y1 = lane_t[d + 1, col + c0 : col + c1]
            y2 = lane_t[d + 2, col + c0 : col + c1]
            y3 = lane_t[d + 3, col + c0 : col + c1]
            for c in range(width):
                a = y0[c]
                b = y1[c]
                e = y2[c]
                f = y3[c]
                r0[c] += x0 * a + x1 * b + x2 * e + x3 * f
                r1[c] += z0 * a + z1 * b + z2 * e + z3 * f
            d += 4
        while d < dim:
            x0 = xa[i, d]
            z0 = xa[i + 1, d]
            y0 = lane_t[d, col + c0 : col + c1]
            for c in range(width):
                r0[c] += x0 * y0[c]
                r1[c] += z0 * y0[c]
            d += 1
        i += 2
    if i < na:
        c0 = lo[i] * _LANES
        c1 = hi[i] * _LANES
        r0 = g[i, c0:c1]
        for c in range(c1 - c0):
            r0[c] = 0.0
        for d in range(dim):
            x0 = xa[i, d]
            y0 = lane_t[d, col + c0 : col + c1]
            for c in range(c1 - c0):
                r0[c] += x0 * y0[c]


@njit(cache=True)
def _costs(
    xa: np.ndarray,
    sqa: np.ndarray,
    lane_t: np.ndarray,
    lane_sq: np.ndarray,
    col: int,
    lo: np.ndarray,
    hi: np.ndarray,
    g: np.ndarray,
) -> None:
    """Turn the dot products in g (row i: lanes [lo[i], hi[i])) into Euclidean local costs,
    in place."""
    na = xa.shape[0]
    dim = xa.shape[1]
    for i in range(na):
        s = sqa[i]
        c0 = lo[i] * _LANES
        c1 = hi[i] * _LANES
        width = c1 - c0
        # slices indexed from 0: loops the compiler can vectorise (no negative-index checks)
        row = g[i, c0:c1]
        other = lane_sq[col + c0 : col + c1]
        small = 0
        for c in range(width):
            t = s + other[c]
            v = t - 2.0 * row[c]
            row[c] = v
            small += v <= _EXACT_TOL * t
        if small:
            for c in range(width):
                if row[c] <= _EXACT_TOL * (s + other[c]):
                    v = 0.0
                    for d in range(dim):
                        diff = xa[i, d] - lane_t[d, col + c0 + c]
                        v += diff * diff
                    row[c] = v
        for c in range(width):
            row[c] = np.sqrt(row[c])


@njit(cache=True)
def _band(na: int, nb: int, window: int, lo: np.ndarray, hi: np.ndarray) -> None:
    """lo[i], hi[i]: the columns j in [lo[i], hi[i]) the window allows row i (module
    docstring); all of them for window -1."""
    for i in range(na):
        if window >= 0:
            lo[i] = max(0, i - window - max(0, na - nb))
            hi[i] = min(nb, i + window + max(0, nb - na) + 1)
        else:
            lo[i] = 0
            hi[i] = nb


@njit(parallel=True, cache=True)
def _matrix_kernel(
    steps: np.ndarray,
    sq: np.ndarray,
    offsets: np.ndarray,
    ln: np.ndarray,
    order: np.ndarray,
    lane_t: np.ndarray,
    lane_sq: np.ndarray,
    batch_col: np.ndarray,
    batch_len: np.ndarray,
    members: np.ndarray,
    first_batch: np.ndarray,
    window: int,
    perm: np.ndarray,
    out: np.ndarray,
) -> None:
    n = ln.shape[0]
    n_batches = batch_len.shape[0]
    maxlen = 0
    for s in range(n):
        maxlen = max(maxlen, ln[s])
    inf = np.inf
    for t in prange(order.shape[0]):  # the rows of this launch
        a = order[t]
        na = ln[a]
        xa = steps[offsets[a] : offsets[a] + na]
        sqa = sq[offsets[a] : offsets[a] + na]
        prev = np.empty((maxlen + 1, _LANES))
        cur = np.empty((maxlen + 1, _LANES))
        g = np.empty((maxlen, maxlen * _LANES))
        lo_row = np.empty(maxlen, dtype=np.int64)
        hi_row = np.empty(maxlen, dtype=np.int64)
        for b in range(first_batch[a], n_batches):
            nb = batch_len[b]
            col = batch_col[b]
            _band(na, nb, window, lo_row, hi_row)
            if window < 0:
                _products_full(xa, lane_t, col, nb * _LANES, g)
                _costs_full(xa, sqa, lane_t, lane_sq, col, nb * _LANES, g)
            else:
                _products(xa, lane_t, col, lo_row, hi_row, g)
                _costs(xa, sqa, lane_t, lane_sq, col, lo_row, hi_row, g)
            # R row -1: 0 before the first column, inf elsewhere
            for j in range(nb + 1):
                for k in range(_LANES):
                    prev[j, k] = inf
            for k in range(_LANES):
                prev[0, k] = 0.0
            for i in range(na):
                lo = lo_row[i]
                hi = hi_row[i]
                for j in range(lo + 1):
                    for k in range(_LANES):
                        cur[j, k] = inf
                for j in range(lo, hi):
                    for k in range(_LANES):
                        m = min(prev[j, k], prev[j + 1, k], cur[j, k])
                        cur[j + 1, k] = g[i, j * _LANES + k] + m
                for j in range(hi, nb):
                    for k in range(_LANES):
                        cur[j + 1, k] = inf
                prev, cur = cur, prev
            for k in range(_LANES):
                other = members[b, k]
                if other > a and (k == 0 or other != members[b, k - 1]):
                    p = perm[a]
                    q = perm[other]
                    if p > q:
                        p, q = q, p
                    out[n * p - (p * (p + 1)) // 2 + q - p - 1] = prev[nb, k]


@njit(cache=True)
def _pair_distance(x: np.ndarray, y: np.ndarray, window: int) -> float:
    """One DTW distance, local costs from differences (the matrix kernel's reference)."""
    n = x.shape[0]
    m = y.shape[0]
    dim = x.shape[1]
    inf = np.inf
    prev = np.full(m + 1, inf)
    cur = np.full(m + 1, inf)
    prev[0] = 0.0
    for i in range(n):
        lo = 0
        hi = m
        if window >= 0:
            lo = max(0, i - window - max(0, n - m))
            hi = min(m, i + window + max(0, m - n) + 1)
        cur[:] = inf
        for j in range(lo, hi):
            v = 0.0
            for d in range(dim):
                diff = x[i, d] - y[j, d]
                v += diff * diff
            cur[j + 1] = np.sqrt(v) + min(prev[j], prev[j + 1], cur[j])
        prev, cur = cur, prev
    return float(prev[m])
