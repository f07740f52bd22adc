import numpy as np
import pytest

from groupwise.behaviour.features import (
    fit_standardiser,
    pool_features,
    raw_sequences,
    step_features,
)
from groupwise.episodes.fragments import Fragment


def fragment(obs: np.ndarray, acts: np.ndarray, start: int = 0) -> Fragment:
    return Fragment(
        obs=obs,
        acts=acts,
        true_rewards=np.zeros(len(obs)),
        episode=0,
        start=start,
        reset_seed=0,
    )


def test_step_features_concatenate_observation_and_action():
    f = fragment(np.array([[1.0, 2.0], [3.0, 4.0]]), np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]))
    np.testing.assert_array_equal(
        step_features(f), [[1.0, 2.0, 0.0, 1.0, 0.0], [3.0, 4.0, 1.0, 0.0, 0.0]]
    )
    assert step_features(f).dtype == np.float64


def test_pool_is_z_scored_per_dimension():
    rng = np.random.default_rng(0)
    scales = np.array([1.0, 100.0, 1e-3])
    seqs = [rng.normal(size=(length, 3)) * scales + 5.0 for length in (4, 7, 30)]
    out = pool_features(seqs)
    assert [s.shape for s in out] == [(4, 3), (7, 3), (30, 3)]
    steps = np.concatenate(out)
    np.testing.assert_allclose(steps.mean(axis=0), 0.0, atol=1e-12)
    np.testing.assert_allclose(steps.std(axis=0), 1.0)


def test_constant_dimension_becomes_zero_not_nan():
    seqs = [np.array([[1.0, 7.0], [2.0, 7.0]]), np.array([[3.0, 7.0]])]
    out = pool_features(seqs)
    np.testing.assert_array_equal(np.concatenate(out)[:, 1], 0.0)
    np.testing.assert_allclose(np.concatenate(out)[:, 0], [-1.224744871391589, 0.0, 1.22474487])
    assert fit_standardiser(raw_sequences(seqs)).constant.tolist() == [False, True]


def test_fragments_and_arrays_mix():
    f = fragment(np.array([[0.0], [2.0]]), np.array([[1.0], [1.0]]))
    out = pool_features([f, np.array([[4.0, 3.0]])])
    np.testing.assert_allclose(out[0][:, 0], [-1.22474487, 0.0])
    np.testing.assert_allclose(out[1][0], [1.22474487, 1.41421356])


@pytest.mark.parametrize(
    "items",
    [
        [],
        [np.ones((2, 2)), np.ones((2, 3))],
        [np.ones((0, 2))],
        [np.array([[np.inf, 0.0]])],
    ],
)
def test_invalid_pools_raise(items):
    with pytest.raises(ValueError):
        pool_features(items)
