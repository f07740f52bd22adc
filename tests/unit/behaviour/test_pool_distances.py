"""A pool measures its distances with the tree config's DTW band and time step."""

import numpy as np

from groupwise.behaviour import TreeConfig, build_tree, dtw_matrix, pool_features
from groupwise.pool.behaviours import BehaviourPool
from groupwise.pool.fragments import Fragment


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
    coarse = TreeConfig(dtw_window=4, dtw_stride=2)
    np.testing.assert_array_equal(pool.distances, dtw_matrix(features))
    np.testing.assert_array_equal(
        pool.measure_distances(cfg=coarse), dtw_matrix(features, window=4, stride=2)
    )
    assert not np.array_equal(pool.measure_distances(cfg=coarse), pool.distances)
    assert pool.tree(coarse) == build_tree(dtw_matrix(features, window=4, stride=2), coarse)
    assert pool.tree() == build_tree(pool.distances, TreeConfig())
