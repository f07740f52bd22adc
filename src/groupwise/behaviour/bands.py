"""Level bands of the behaviour tree (SPEC §4; `behaviour.tree`, step 2): the thresholds
t_1 <= ... <= t_levels = D that cut a dendrogram's merge heights into levels, and the level
of each merge.
"""

from collections.abc import Callable, Sequence

import numpy as np

from groupwise.types import FloatArray


def linear_thresholds(heights: FloatArray, levels: int) -> tuple[float, ...]:
    """t_k = D k / levels for k = 1..levels (SPEC §4); D the highest merge."""
    root_height = _root_height(heights)
    out = [root_height * k / levels for k in range(1, levels)]
    return (*out, root_height)


def geometric_thresholds(heights: FloatArray, levels: int) -> tuple[float, ...]:
    """t_k = D 2^(k - levels) for k = 1..levels: D/8, D/4, D/2, D for 4 levels."""
    root_height = _root_height(heights)
    out = [root_height * 2.0 ** (k - levels) for k in range(1, levels)]
    return (*out, root_height)


def count_thresholds(heights: FloatArray, levels: int) -> tuple[float, ...]:
    """Thresholds that leave about N / k^l clusters at level l, k = N^(1/levels) (module
    docstring); `heights` are the N − 1 merge heights in ascending order."""
    h = np.sort(np.asarray(heights, dtype=np.float64))
    n = len(h) + 1
    if n < 2:
        return tuple([0.0] * levels)
    k = n ** (1.0 / levels)
    out = []
    for level in range(1, levels):
        clusters = max(1, round(n / k**level))
        out.append(float(h[min(max(n - clusters, 0), n - 2)]))
    return (*out, float(h[-1]))


def _root_height(heights: FloatArray) -> float:
    return float(np.max(heights)) if len(heights) else 0.0


BANDS: dict[str, Callable[[FloatArray, int], tuple[float, ...]]] = {
    "counts": count_thresholds,
    "linear": linear_thresholds,
    "geometric": geometric_thresholds,
}
"""Band name -> thresholds (levels,) from the merge heights and the number of levels."""


def assign_levels(heights: FloatArray, thresholds: Sequence[float]) -> np.ndarray:
    """(M,) level of each merge height: the first k with t_k > h, else the top level."""
    t = np.asarray(thresholds, dtype=np.float64)
    first_above = np.searchsorted(t, np.asarray(heights, dtype=np.float64), side="right")
    return np.minimum(first_above + 1, len(t)).astype(np.int64)
