"""Statistics of a study, as pure functions of score arrays (no I/O, no plotting).

Scores follow rliable's shape: ``{method: array[runs, tasks]}``, here ``{dm: array[seeds,
envs]}`` of final true returns, with NaN where a cell is missing. Every function ignores NaN.
"""

import math
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np
from scipy import stats

from groupwise.types import FloatArray

Scores = Mapping[str, FloatArray]
"""``{dm: array[runs, envs]}``; NaN marks a missing run."""


@dataclass(frozen=True)
class Interval:
    low: float
    high: float


@dataclass(frozen=True)
class TTest:
    """A two-sided Welch t-test of mean(a) − mean(b)."""

    t: float
    df: float
    p: float


def mean_sd(values: FloatArray) -> tuple[float, float]:
    """Mean and sample SD (ddof = 1) of the finite values; NaN for what is undefined."""
    x = _finite(values)
    mean = float(x.mean()) if x.size else math.nan
    sd = float(x.std(ddof=1)) if x.size > 1 else math.nan
    return mean, sd


def iqr_bounds(values: FloatArray) -> tuple[float, float]:
    """First and third quartile of the finite values (NumPy's linear interpolation)."""
    x = _finite(values)
    if not x.size:
        return math.nan, math.nan
    q1, q3 = np.percentile(x, [25, 75])
    return float(q1), float(q3)


def iqr_normalise(scores: Scores) -> dict[str, FloatArray]:
    """Scale each env so the interquartile range over all runs of all DMs maps to [0, 1].

    For env j with quartiles Q1, Q3 over every run of every DM: x ↦ (x − Q1) / (Q3 − Q1)
    (the paper's normalisation, §5 of its study). An env whose quartiles coincide is only
    shifted (divided by 1), so it neither explodes nor vanishes.

    Args:
        scores: ``{dm: array[runs, envs]}``, the same number of envs for every DM.
    Returns:
        The same shapes, normalised; NaN stays NaN.
    """
    arrays = {dm: np.asarray(a, dtype=float) for dm, a in scores.items()}
    if not arrays:
        return {}
    n_envs = {a.shape[1] for a in arrays.values()}
    if len(n_envs) != 1:
        raise ValueError(
            f"every DM needs the same envs, got shapes {[a.shape for a in arrays.values()]}"
        )
    pooled = np.concatenate(list(arrays.values()), axis=0)  # (all runs, envs)
    q1 = np.empty(pooled.shape[1])
    scale = np.empty(pooled.shape[1])
    for j in range(pooled.shape[1]):
        low, high = iqr_bounds(pooled[:, j])
        q1[j] = low
        scale[j] = high - low if high > low else 1.0
    return {dm: (a - q1) / scale for dm, a in arrays.items()}


def iqm(values: FloatArray) -> float:
    """Interquartile mean: the mean of the middle 50 % of the finite values (25 % cut each
    side, as `scipy.stats.trim_mean` and rliable cut)."""
    x = _finite(values)
    return float(stats.trim_mean(x, 0.25)) if x.size else math.nan


def iqm_rows(samples: FloatArray) -> FloatArray:
    """`iqm` of every row of a (rows, n) array without NaN, shape (rows,)."""
    return np.asarray(stats.trim_mean(samples, 0.25, axis=1), dtype=float)


def stratified_bootstrap_ci(
    scores: FloatArray,
    rng: np.random.Generator,
    statistic: Callable[[FloatArray], FloatArray] = iqm_rows,
    reps: int = 2000,
    level: float = 0.95,
) -> Interval:
    """Percentile bootstrap interval of `statistic` over all runs of all envs.

    Each replicate resamples the runs of every env (column) with replacement, separately per
    env (rliable's stratified bootstrap), so every env keeps its number of runs.

    Args:
        scores: array[runs, envs]; NaN runs are dropped per env.
        statistic: maps the replicates, shape (reps, finite runs), to one value per
            replicate, shape (reps,); by default the IQM.
    """
    columns = [_finite(c) for c in np.asarray(scores, dtype=float).T]
    columns = [c for c in columns if c.size]
    if not columns:
        return Interval(math.nan, math.nan)
    samples = np.concatenate(
        [c[rng.integers(0, c.size, size=(reps, c.size))] for c in columns], axis=1
    )  # (reps, finite runs)
    values = statistic(samples)
    alpha = (1.0 - level) / 2.0
    low, high = np.percentile(values, [100 * alpha, 100 * (1 - alpha)])
    return Interval(float(low), float(high))


def welch_t_test(a: FloatArray, b: FloatArray) -> TTest:
    """Two-sided Welch t-test (unequal variances) of the finite values of `a` and `b`
    (`scipy.stats.ttest_ind` with ``equal_var=False``).

    NaN (t, df and p) when either side has fewer than two values or both are constant:
    SciPy would answer those with a NaN t but df = 1, and warn.
    """
    x, y = _finite(a), _finite(b)
    if x.size < 2 or y.size < 2 or (np.ptp(x) == 0 and np.ptp(y) == 0):
        return TTest(math.nan, math.nan, math.nan)
    with warnings.catch_warnings():
        # An exactly constant side has variance 0, which SciPy reports as "precision loss".
        warnings.filterwarnings("ignore", "Precision loss", RuntimeWarning)
        result = stats.ttest_ind(x, y, equal_var=False)
    return TTest(float(result.statistic), float(result.df), float(result.pvalue))


def relative_difference(a: float, b: float) -> float:
    """(a − b) / |b|, the paper's "x % higher than"; NaN when b is 0 or NaN."""
    return (a - b) / abs(b) if b and math.isfinite(b) else math.nan


def confidence_band(
    curves: FloatArray, level: float = 0.95
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Mean and Student-t confidence band of the mean across runs, per point.

    Args:
        curves: array[runs, points]; NaN where a run has no value at that point.
    Returns:
        (mean, low, high), each of shape (points,); the band is NaN where fewer than two
        runs have a value.
    """
    x = np.asarray(curves, dtype=float)
    n = np.sum(np.isfinite(x), axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.nansum(x, axis=0) / n
        centred = np.where(np.isfinite(x), x - mean, 0.0)
        sd = np.sqrt(np.sum(centred**2, axis=0) / (n - 1))
        half = stats.t.ppf(0.5 + level / 2.0, np.maximum(n - 1, 1)) * sd / np.sqrt(n)
    half = np.where(n >= 2, half, np.nan)
    mean = np.where(n >= 1, mean, np.nan)
    return mean, mean - half, mean + half


def _finite(values: FloatArray) -> FloatArray:
    x = np.asarray(values, dtype=float).ravel()
    return x[np.isfinite(x)]
