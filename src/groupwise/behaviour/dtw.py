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

Speed. One numba kernel (`dtw_kernels`) computes all N (N - 1) / 2 distances, parallel
over rows of the matrix, launched on about a tenth of the rows at a time to report progress;
sorted by length, runs of equal-length sequences fill its 8 vector lanes (`_batches`). No
O((N L)^2) matrix is ever held: memory is O(N L D). See `benchmarks/dtw.py` for timings.
The first call compiles the kernels (or loads them from numba's on-disk cache); `warm_up`
does that explicitly. Threads and processes: `dtw_threads` (a process that computes
distances starts its workers with "spawn" or "forkserver"; every launch restores the OpenMP
limits it found).
"""

import math
import time
from collections.abc import Sequence

import numba
import numpy as np
from threadpoolctl import threadpool_limits

from groupwise.behaviour.dtw_kernels import LANES, matrix_kernel, pair_distance
from groupwise.types import FloatArray, IntArray, ProgressFn


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
    return float(pair_distance(coarsen(a, s), coarsen(b, s), w)) * s


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
    batch_col[1:] = np.cumsum(batch_len * LANES)
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
            matrix_kernel(
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
        while j < n and j - i < LANES and lengths[j] == lengths[i]:
            j += 1
        members.append(list(range(i, j)) + [j - 1] * (LANES - (j - i)))
        batch_len.append(lengths[i])
        i = j
    return np.array(members, dtype=np.int64), np.array(batch_len, dtype=np.int64)
