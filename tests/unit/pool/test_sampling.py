"""A round's pool: enough windows, the most uncertain kept, or a random subset."""

import numpy as np
import pytest

from groupwise.config import RewardConfig
from groupwise.envs import make_env
from groupwise.episodes.fragments import stack_fragments, tile_fragments
from groupwise.pool.sampling import sample_pool, windows_to_sample
from groupwise.pool.sources import CurrentPolicy, PolicyVariants
from groupwise.reward import RewardEnsemble
from groupwise.rl.policy import RandomPolicy, biased_variants


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


class _Constant:
    """A policy that always takes `action` (Pendulum: a torque)."""

    def __init__(self, action: float) -> None:
        self.action = action

    def act(self, obs, rng):
        return np.full((obs.shape[0], 1), self.action, dtype=np.float32)


def test_biased_variants_push_the_actions_one_way_within_the_bounds():
    space = make_env("Pendulum-v1").action_space  # Box(-2, 2, (1,))
    obs = np.zeros((4, 3), dtype=np.float32)
    rng = np.random.default_rng(0)
    variants = biased_variants(_Constant(0.0), space, 50, 0.5, rng)
    offsets = np.array([v.act(obs, rng)[0, 0] for v in variants])
    assert np.all(np.abs(offsets) <= 1.0) and offsets.std() > 0.3  # up to half of half the range
    for variant in variants:  # the same push at every step and for every observation
        assert np.ptp(variant.act(obs, rng)) == 0
    pushed = biased_variants(_Constant(1.9), space, 20, 1.0, rng)
    assert max(v.act(obs, rng)[0, 0] for v in pushed) == 2.0  # clipped to the bound
    grid = make_env("GridWorld").action_space
    always = biased_variants(RandomPolicy(grid), grid, 3, 1.0, rng)
    for variant in always:  # share 1: its own action at every step
        assert len(set(variant.act(np.zeros((50, 2)), rng).tolist())) == 1
    with pytest.raises(ValueError, match="scale in"):
        biased_variants(_Constant(0.0), space, 2, 1.5, rng)


def test_a_share_of_the_pool_comes_from_the_variants():
    def pendulum():
        return make_env("Pendulum-v1")

    policy = _Constant(0.0)

    def sample(share: float, variants: int = 3):
        sources = [CurrentPolicy(), PolicyVariants(variants, share)] if variants else None
        return sample_pool(
            pendulum, policy, 36, 30, np.random.default_rng(1), sources=sources, processes=1
        )

    pool = sample(0.5)
    episodes = pool.episodes
    assert [e.episode for e in episodes] == list(range(len(episodes)))
    pushes = [float(e.actions[0, 0]) for e in episodes]
    assert all(np.all(e.actions == e.actions[0]) for e in episodes)  # one push an episode
    # 18 windows of the policy's own (three 200-step episodes of 6), then 6 of each variant
    assert pushes[:3] == [0.0] * 3 and all(p != 0.0 for p in pushes[3:]) and len(pushes) == 6
    assert [e.source for e in episodes] == [0, 0, 0, 1, 2, 3]  # who played each episode
    assert len(pool) == 36
    # a variant's offsets are drawn first, from the pool's stream: no share, other windows
    alone, unshared = sample(0.0, variants=0), sample(0.0)
    assert [e.source for e in unshared.episodes] == [0] * 6
    assert not all(
        np.array_equal(a.obs, b.obs)
        for a, b in zip(alone.fragments, unshared.fragments, strict=True)
    )
