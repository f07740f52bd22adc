"""The numba kernels behind `dtw.dtw_matrix` and `dtw.dtw_distance` (definition, window
and stride: `behaviour.dtw`'s docstring).

Speed. All N (N - 1) / 2 distances are computed by one kernel, `matrix_kernel`, parallel over
rows of the matrix (launched on about a tenth of the rows at a time, to report progress). The
local costs come from ||x||^2 + ||y||^2 - 2 x.y: the dot products are the only O(L^2 D)
work per pair and run as dense vectorised loops; every cost whose squared value is within
a relative `_EXACT_TOL` of cancellation is recomputed directly from the differences, so
identical steps cost exactly 0 and every cost keeps a relative error below about D * 1e-12.
The loops that turn products into costs run over slices indexed from 0 so that they are
vectorised, square roots included (indexed from the band's first column they compiled to
scalar code and took 60 % of a banded Hopper matrix; issue 22).
The dynamic programme runs on 8 pairs at once (one vector lane per pair: row a against 8
sequences of equal length). No O((N L)^2) matrix is ever held: memory is O(N L D). See
`benchmarks/dtw.py` for timings. `pair_distance` is the matrix kernel's reference: one
pair, local costs from differences.

Windows reach the kernels as an int radius, -1 for none.
"""

import numpy as np
from numba import njit, prange

LANES = 8
"""Pairs per dynamic-programme step: one AVX-512 register, or two AVX2 registers, of float64."""
_EXACT_TOL = 1e-4
"""Squared costs below this fraction of ||x||^2 + ||y||^2 are recomputed from differences:
cancellation in the dot-product form loses log10(1 / (relative cost)) digits."""


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
    (times `LANES`: the steps of the other sequences a band allows row i).

    Two rows and four dimensions per pass keep the vector loop's loads per FMA low; a pass
    covers the union of its two rows' ranges. Every value is summed in the same order
    whatever the ranges, so a band changes which cells are computed, never their values.
    """
    na = xa.shape[0]
    dim = xa.shape[1]
    i = 0
    while i + 1 < na:
        c0 = min(lo[i], lo[i + 1]) * LANES
        c1 = max(hi[i], hi[i + 1]) * LANES
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
        c0 = lo[i] * LANES
        c1 = hi[i] * LANES
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
        c0 = lo[i] * LANES
        c1 = hi[i] * LANES
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
def matrix_kernel(
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
    """Write the distances of the rows `order` (sorted positions) to every later sequence into
    the condensed `out`, in input order (`perm`: sorted position -> input index). The steps,
    their squared norms and the lane layout are as `dtw.dtw_matrix` builds them; `window` is
    a radius in steps, -1 for none."""
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
        prev = np.empty((maxlen + 1, LANES))
        cur = np.empty((maxlen + 1, LANES))
        g = np.empty((maxlen, maxlen * LANES))
        lo_row = np.empty(maxlen, dtype=np.int64)
        hi_row = np.empty(maxlen, dtype=np.int64)
        for b in range(first_batch[a], n_batches):
            nb = batch_len[b]
            col = batch_col[b]
            _band(na, nb, window, lo_row, hi_row)
            if window < 0:
                _products_full(xa, lane_t, col, nb * LANES, g)
                _costs_full(xa, sqa, lane_t, lane_sq, col, nb * LANES, g)
            else:
                _products(xa, lane_t, col, lo_row, hi_row, g)
                _costs(xa, sqa, lane_t, lane_sq, col, lo_row, hi_row, g)
            # R row -1: 0 before the first column, inf elsewhere
            for j in range(nb + 1):
                for k in range(LANES):
                    prev[j, k] = inf
            for k in range(LANES):
                prev[0, k] = 0.0
            for i in range(na):
                lo = lo_row[i]
                hi = hi_row[i]
                for j in range(lo + 1):
                    for k in range(LANES):
                        cur[j, k] = inf
                for j in range(lo, hi):
                    for k in range(LANES):
                        m = min(prev[j, k], prev[j + 1, k], cur[j, k])
                        cur[j + 1, k] = g[i, j * LANES + k] + m
                for j in range(hi, nb):
                    for k in range(LANES):
                        cur[j + 1, k] = inf
                prev, cur = cur, prev
            for k in range(LANES):
                other = members[b, k]
                if other > a and (k == 0 or other != members[b, k - 1]):
                    p = perm[a]
                    q = perm[other]
                    if p > q:
                        p, q = q, p
                    out[n * p - (p * (p + 1)) // 2 + q - p - 1] = prev[nb, k]


@njit(cache=True)
def pair_distance(x: np.ndarray, y: np.ndarray, window: int) -> float:
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
