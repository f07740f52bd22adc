"""A pool measures its distances with the tree config's DTW band and time step."""

import numpy as np
import pytest

from groupwise.behaviour import TreeConfig, band_window, build_tree, dtw_matrix, pool_features
from groupwise.behaviour.pool import BehaviourPool
from groupwise.episodes.fragments import Fragment


def _pool(n: int = 12, length: int = 20) -> BehaviourPool:
    rng = np.random.default_rng(0)
    fragments = tuple(
        Fragment(
            obs=rng.normal(size=(length, 3)),
            acts=rng.uniform(-1, 1, size=(length, 2)),
            true_rewards=np.zeros(length),
            episode=i,
            start=0,
            reset_seed=i,
        )
        for i in range(n)
    )
    return BehaviourPool(0, fragments, np.zeros((n, 0)))


def test_the_tree_uses_its_configs_dtw_settings():
    pool = _pool()
    features = pool_features(pool.fragments)
    coarse = TreeConfig(dtw_band=0.2, dtw_stride=2)  # radius 4 of 20 steps
    np.testing.assert_array_equal(pool.distances, dtw_matrix(features, window=4))
    exact = TreeConfig(dtw_band=None)
    np.testing.assert_array_equal(pool.measure_distances(cfg=exact), dtw_matrix(features))
    np.testing.assert_array_equal(
        pool.measure_distances(cfg=coarse), dtw_matrix(features, window=4, stride=2)
    )
    assert not np.array_equal(pool.measure_distances(cfg=coarse), pool.distances)
    assert pool.tree(coarse) == build_tree(dtw_matrix(features, window=4, stride=2), coarse)
    assert pool.tree() == build_tree(pool.distances, TreeConfig())


def test_band_window():
    assert band_window(0.2, 188) == 38
    assert band_window(0.2, 20) == 4
    assert band_window(0.1, 30) == 3
    assert band_window(None, 30) is None
    with pytest.raises(ValueError):
        band_window(0.0, 30)
