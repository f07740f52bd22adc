"""Agglomerative clustering of a pool on its precomputed DTW distances (SPEC §4), via SciPy.

Methods (`LINKAGE_METHODS`):
- "complete" (default): a merge's height is the largest distance between its two sides.
- "average": the mean distance between the two sides (UPGMA).
- "ward": SciPy's Ward update (Lance–Williams). It is exact Ward only for Euclidean
  distances; DTW distances are not Euclidean, so this is "Ward-like": it still merges the
  pair that least increases a within-cluster spread computed by the same recurrence, and
  its heights are still monotone, but they are not variances of any point set.

All three give monotone merge heights (a parent is never lower than its children), which the
tree's level bands rely on.
"""

from collections.abc import Callable

import numpy as np
from scipy.cluster.hierarchy import leaves_list, linkage
from scipy.spatial.distance import squareform

from groupwise.types import FloatArray, IntArray

LINKAGE_METHODS: dict[str, Callable[[FloatArray], FloatArray]] = {
    "complete": lambda d: linkage(d, method="complete"),
    "average": lambda d: linkage(d, method="average"),
    "ward": lambda d: linkage(d, method="ward"),
}
"""Linkage name -> function from condensed distances to a SciPy linkage matrix (N - 1, 4)."""


def pool_size(n_distances: int) -> int:
    """N such that N (N - 1) / 2 == n_distances; raises ValueError if there is none."""
    n = int((1 + np.sqrt(1 + 8 * n_distances)) / 2)
    while n * (n - 1) // 2 > n_distances:
        n -= 1
    while n * (n - 1) // 2 < n_distances:
        n += 1
    if n * (n - 1) // 2 != n_distances:
        raise ValueError(f"{n_distances} is not a condensed distance count N (N - 1) / 2")
    return max(n, 1)


def as_condensed(distances: FloatArray) -> FloatArray:
    """Validated float64 condensed distances (N (N - 1) / 2,) from condensed or square input.

    A square input (N, N) must be symmetric with a zero diagonal. Raises ValueError for
    negative or non-finite distances.
    """
    d = np.asarray(distances, dtype=np.float64)
    if d.ndim == 2:
        if d.shape[0] != d.shape[1]:
            raise ValueError(f"a distance matrix must be square, got {d.shape}")
        if not np.allclose(d, d.T) or np.any(np.diag(d) != 0):
            raise ValueError("a square distance matrix must be symmetric with a zero diagonal")
        d = squareform(d, checks=False) if d.shape[0] > 1 else np.zeros(0)
    if d.ndim != 1:
        raise ValueError(f"expected condensed (M,) or square (N, N) distances, got {d.shape}")
    pool_size(d.shape[0])
    if not np.isfinite(d).all() or (d < 0).any():
        raise ValueError("distances must be finite and non-negative")
    return d


def linkage_matrix(distances: FloatArray, method: str = "complete") -> FloatArray:
    """SciPy linkage matrix (N - 1, 4) of condensed distances (N (N - 1) / 2,), N >= 2.

    Row r merges clusters Z[r, 0] (left) and Z[r, 1] (right) into cluster N + r at height
    Z[r, 2]; Z[r, 3] is its size.
    """
    if method not in LINKAGE_METHODS:
        raise ValueError(f"unknown linkage {method!r}; choose from {sorted(LINKAGE_METHODS)}")
    d = as_condensed(distances)
    if pool_size(d.shape[0]) < 2:
        raise ValueError("clustering needs at least 2 behaviours")
    return LINKAGE_METHODS[method](d)


def leaf_order(z: FloatArray) -> IntArray:
    """(N,) the dendrogram's left-to-right leaf order (`scipy.cluster.hierarchy.leaves_list`)."""
    return leaves_list(z)
