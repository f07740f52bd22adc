"""Study statistics on hand-checkable numbers: IQR normalisation, IQM, bootstrap, Welch t."""

import math

import numpy as np
import pytest
from scipy import stats

from groupwise.study.simulation.statistics import (
    confidence_band,
    iqm,
    iqr_bounds,
    iqr_normalise,
    mean_sd,
    relative_difference,
    stratified_bootstrap_ci,
    welch_t_test,
)

NAN = math.nan


def test_iqr_normalisation_maps_each_envs_quartiles_to_zero_and_one():
    # env 0 pools 0, 4, 1, 3, 2 (the NaN is a missing run): Q1 = 1, Q3 = 3, so x ↦ (x − 1) / 2.
    # env 1 is constant (Q1 = Q3 = 7): only shifted, not divided by zero.
    scores = {
        "a": np.array([[0.0, 7.0], [4.0, 7.0]]),
        "b": np.array([[1.0, 7.0], [3.0, 7.0]]),
        "c": np.array([[2.0, 7.0], [NAN, 8.0]]),
    }
    normalised = iqr_normalise(scores)
    np.testing.assert_allclose(normalised["a"], [[-0.5, 0.0], [1.5, 0.0]])
    np.testing.assert_allclose(normalised["b"], [[0.0, 0.0], [1.0, 0.0]])
    np.testing.assert_allclose(normalised["c"], [[0.5, 0.0], [NAN, 1.0]])
    pooled = np.concatenate([normalised[k][:, 0] for k in scores])
    assert iqr_bounds(pooled) == pytest.approx((0.0, 1.0))


def test_iqr_normalisation_needs_the_same_envs_for_every_dm():
    with pytest.raises(ValueError, match="same envs"):
        iqr_normalise({"a": np.zeros((2, 2)), "b": np.zeros((2, 3))})


def test_iqr_bounds_use_linear_interpolation():
    # positions 0.75 and 2.25 of the sorted (1, 2, 3, 5)
    assert iqr_bounds(np.array([5.0, 1.0, 3.0, 2.0])) == pytest.approx((1.75, 3.5))


def test_iqm_is_the_mean_of_the_middle_half():
    assert iqm(np.arange(1.0, 9.0)) == pytest.approx(4.5)  # mean of 3, 4, 5, 6
    assert iqm(np.array([1, 2, 3, 4, 5, 6, 7, 1000.0])) == pytest.approx(4.5)  # robust
    assert iqm(np.array([[1.0, NAN], [2.0, 3.0], [4.0, NAN]])) == pytest.approx(2.5)
    assert math.isnan(iqm(np.array([NAN])))


def test_bootstrap_interval_of_two_coin_values_spans_both():
    # Means of 2 draws from {0, 1}: 0 (p = 1/4), 0.5 (1/2), 1 (1/4): the 95 % interval is [0, 1].
    scores = np.array([[0.0], [1.0]])
    interval = stratified_bootstrap_ci(
        scores, np.random.default_rng(0), statistic=lambda s: s.mean(axis=1)
    )
    assert (interval.low, interval.high) == (0.0, 1.0)


def test_bootstrap_is_stratified_per_env():
    # Env 0 is all 0, env 1 all 10: every replicate keeps two of each, so the mean is always 5
    # (pooling the runs before resampling would not).
    scores = np.array([[0.0, 10.0], [0.0, 10.0]])
    interval = stratified_bootstrap_ci(
        scores, np.random.default_rng(1), statistic=lambda s: s.mean(axis=1)
    )
    assert (interval.low, interval.high) == (5.0, 5.0)


def test_bootstrap_iqm_interval_is_seeded_and_contains_the_iqm():
    scores = np.random.default_rng(7).normal(size=(5, 6))
    first = stratified_bootstrap_ci(scores, np.random.default_rng(3), reps=500)
    again = stratified_bootstrap_ci(scores, np.random.default_rng(3), reps=500)
    assert first == again
    assert first.low < iqm(scores) < first.high


def test_welch_t_test_matches_scipy():
    rng = np.random.default_rng(5)
    a, b = rng.normal(1.0, 1.0, size=12), rng.normal(0.0, 3.0, size=7)
    ours = welch_t_test(a, b)
    theirs = stats.ttest_ind(a, b, equal_var=False)
    assert ours.t == pytest.approx(theirs.statistic)
    assert ours.p == pytest.approx(theirs.pvalue)
    assert ours.df == pytest.approx(theirs.df)


def test_welch_t_test_ignores_missing_runs_and_refuses_too_few():
    a = np.array([1.0, 2.0, NAN, 4.0])
    b = np.array([3.0, 5.0, 9.0])
    expected = stats.ttest_ind([1.0, 2.0, 4.0], b, equal_var=False)
    assert welch_t_test(a, b).t == pytest.approx(expected.statistic)
    assert all(math.isnan(v) for v in vars(welch_t_test(np.array([1.0]), b)).values())
    constant = welch_t_test(np.ones(3), np.ones(4))
    assert all(math.isnan(v) for v in vars(constant).values())
    # one constant side is fine: b (mean 17/3, variance 28/3) alone carries it,
    # t = (1 − 17/3) / √(28/9) = −√7
    assert welch_t_test(np.ones(3), b).t == pytest.approx(-math.sqrt(7))


def test_mean_and_sample_sd():
    mean, sd = mean_sd(np.array([1.0, 2.0, 3.0, 4.0, NAN]))
    assert mean == pytest.approx(2.5)
    assert sd == pytest.approx(math.sqrt(5 / 3))  # ddof = 1
    assert math.isnan(mean_sd(np.array([3.0]))[1])


def test_relative_difference():
    assert relative_difference(1.5, 1.0) == pytest.approx(0.5)
    assert relative_difference(1.0, -2.0) == pytest.approx(1.5)
    assert math.isnan(relative_difference(1.0, 0.0))


def test_confidence_band_is_student_t_where_two_runs_exist():
    mean, low, high = confidence_band(np.array([[1.0, 2.0], [3.0, NAN]]))
    np.testing.assert_allclose(mean, [2.0, 2.0])
    half = stats.t.ppf(0.975, 1) * math.sqrt(2.0) / math.sqrt(2.0)  # sd √2, n 2
    assert (low[0], high[0]) == pytest.approx((2.0 - half, 2.0 + half))
    assert math.isnan(low[1]) and math.isnan(high[1])
