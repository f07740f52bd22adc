"""A round's pool: enough windows, the most uncertain kept, or a random subset."""

import numpy as np
import pytest

from groupwise.config import RewardConfig
from groupwise.envs import make_env
from groupwise.pool.fragments import stack_fragments, tile_fragments
from groupwise.pool.sampling import sample_pool, windows_to_sample
from groupwise.reward import RewardEnsemble
from groupwise.rl.policy import RandomPolicy


def _make():
    return make_env("GridWorld")


def test_the_most_uncertain_windows_are_kept_or_a_random_subset():
    rng = np.random.default_rng(0)
    ensemble = RewardEnsemble.for_env(_make, RewardConfig(), rng)
    policy = RandomPolicy(_make().action_space)
    uncertain = sample_pool(
        _make, policy, 20, 30, np.random.default_rng(1), oversample=3.0, ensemble=ensemble
    )
    assert len(uncertain) == 20 and uncertain.predicted_returns.shape == (20, 3)
    windows = sum(len(t) // 30 for t in uncertain.episodes)
    assert windows >= 60  # oversampled: the pool keeps a third of them
    kept = uncertain.predicted_returns.var(axis=1).min()
    # no window left out is more uncertain than the least uncertain one kept
    obs, acts = stack_fragments(tile_fragments(list(uncertain.episodes), 30))
    assert (ensemble.returns(obs, acts).var(axis=1) > kept + 1e-6).sum() < 20
    random = sample_pool(
        _make,
        policy,
        20,
        30,
        np.random.default_rng(1),
        oversample=3.0,
        ensemble=ensemble,
        select="random",
    )
    assert len(random) == 20
    assert {f.key for f in random.fragments} != {f.key for f in uncertain.fragments}
    assert random.step_variance is not None


def test_windows_to_sample_caps_the_windows_not_the_pool():
    assert windows_to_sample(200, 2.0, 1000) == 400  # a pool up to half the cap: 2 × N
    assert windows_to_sample(500, 2.0, 1000) == 1000
    assert windows_to_sample(700, 2.0, 1000) == 1000
    assert windows_to_sample(1000, 2.0, 1000) == 1000 == windows_to_sample(1000, 2.0, 10)
    assert windows_to_sample(1000, 2.0) == 2000  # no limit
    assert windows_to_sample(7, 1.5) == 11
    for size, oversample, cap in ((0, 2.0, 1), (5, 0.5, 1), (5, 2.0, 0)):
        with pytest.raises(ValueError, match="need size"):
            windows_to_sample(size, oversample, cap)


def test_a_capped_oversample_samples_fewer_windows():
    policy = RandomPolicy(_make().action_space)
    ensemble = RewardEnsemble.for_env(_make, RewardConfig(), np.random.default_rng(0))
    pool = sample_pool(
        _make, policy, 20, 30, np.random.default_rng(1), oversample=3.0, max_windows=25,
        ensemble=ensemble,
    )  # fmt: skip
    assert len(pool) == 20
    assert 25 <= sum(len(t) // 30 for t in pool.episodes) < 60
