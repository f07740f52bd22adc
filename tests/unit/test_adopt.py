"""Which pool variant the teacher preferred to the policy (`run.adopt`, issue 20)."""

import numpy as np
import pytest

from groupwise.config import LoopConfig, PPOConfig, RunConfig
from groupwise.envs import make_env
from groupwise.pool.sampling import sample_pool
from groupwise.preferences.pairs import Pair
from groupwise.rl.policy import biased_variants
from groupwise.rl.ppo import PPOAgent
from groupwise.run.adopt import ALPHA, fragment_sources, preferred_variant

# pool indices 0-3 the policy's, 4-7 variant 1's, 8-11 variant 2's: K = 2 variants
SOURCES = [0] * 4 + [1] * 4 + [2] * 4


def _pairs(variant_index: int, labels: list[float]) -> list[Pair]:
    """Pairs of a variant behaviour (left) against a policy one (right)."""
    return [Pair(variant_index, k % 4, label) for k, label in enumerate(labels)]


def test_a_variant_whose_wins_are_significant_is_preferred():
    # one-sided binomial p < 0.05 / 2: 6 of 6 (p 0.016) pass, 5 of 5 (0.031) do not
    assert preferred_variant(SOURCES, _pairs(5, [1.0] * 6)) == 1
    assert preferred_variant(SOURCES, _pairs(5, [1.0] * 5)) is None
    assert preferred_variant(SOURCES, _pairs(9, [1.0] * 8 + [0.0])) == 2  # 8 of 9: p 0.020
    # the same pairs with the policy's behaviour on the left
    flipped = [Pair(p.b, p.a, 1.0 - p.label) for p in _pairs(9, [1.0] * 6)]
    assert preferred_variant(SOURCES, flipped) == 2


def test_equal_answers_count_half_a_win_rounded_down():
    assert preferred_variant(SOURCES, _pairs(5, [1.0] * 6 + [0.5])) is None  # 6 of 7: p 0.06
    assert preferred_variant(SOURCES, _pairs(5, [1.0] * 6 + [0.5] * 2)) is None  # 7 of 8
    assert preferred_variant(SOURCES, _pairs(5, [0.5] * 20)) is None


def test_a_draw_a_loss_or_nothing_adopts_nothing():
    assert preferred_variant(SOURCES, _pairs(5, [1.0, 0.0] * 10)) is None
    assert preferred_variant(SOURCES, _pairs(5, [0.0] * 10)) is None
    assert preferred_variant(SOURCES, []) is None
    assert preferred_variant([0] * 4, [Pair(0, 1, 1.0)] * 10) is None  # no variants at all


def test_only_pairs_against_the_policy_count_and_the_smallest_p_wins():
    among_variants = [Pair(4 + k % 4, 8 + k % 4, 1.0) for k in range(20)]
    among_policy = [Pair(k % 4, (k + 1) % 4, 1.0) for k in range(20)]
    assert preferred_variant(SOURCES, among_variants + among_policy) is None
    assert preferred_variant(SOURCES, _pairs(5, [1.0] * 7) + _pairs(9, [1.0] * 9)) == 2
    assert preferred_variant(SOURCES, _pairs(5, [1.0] * 9) + _pairs(9, [1.0] * 9)) == 1  # tie
    eight = [0] * 4 + [k for k in range(1, 9) for _ in range(4)]  # K = 8: p < 0.00625
    assert preferred_variant(eight, _pairs(5, [1.0] * 7)) is None  # p 0.0078
    assert preferred_variant(eight, _pairs(5, [1.0] * 8)) == 1  # p 0.0039
    assert ALPHA == 0.05


class _Still:
    """A Pendulum policy that never pushes."""

    def act(self, obs, rng):
        return np.zeros((obs.shape[0], 1), dtype=np.float32)


def test_a_pools_behaviours_know_their_source():
    def pendulum():
        return make_env("Pendulum-v1")

    variants = biased_variants(_Still(), pendulum().action_space, 2, 0.5, np.random.default_rng(3))
    pool = sample_pool(
        pendulum, _Still(), 24, 50, np.random.default_rng(1), variants=variants, processes=1
    )
    sources = fragment_sources(pool)
    assert set(sources) == {0, 1, 2}
    for fragment, source in zip(pool.fragments, sources, strict=True):
        pushed = 0.0 if source == 0 else float(variants[source - 1].offset[0])
        assert np.all(fragment.acts == np.float32(pushed))  # played by that source


def test_shifting_the_policy_moves_its_greedy_actions_by_the_offset():
    def pendulum():
        return make_env("Pendulum-v1")

    agent = PPOAgent(
        pendulum, PPOConfig(n_envs=1, n_steps=64, batch_size=32, tensorboard=False), seed=0
    )
    obs = np.random.default_rng(0).normal(size=(16, 3)).astype(np.float32) * 0.1
    rng = np.random.default_rng(0)
    before = agent.act(obs, rng, deterministic=True)
    agent.shift_actions(np.array([0.7], dtype=np.float32))
    after = agent.act(obs, rng, deterministic=True)
    inside = np.abs(before + 0.7) < 2.0  # not clipped at the bound
    assert inside.all()
    np.testing.assert_allclose(after[inside], before[inside] + 0.7, atol=1e-5)
    agent.close()
    grid = PPOAgent(
        lambda: make_env("GridWorld"),
        PPOConfig(n_envs=1, n_steps=64, batch_size=32, tensorboard=False),
        seed=0,
    )
    with pytest.raises(TypeError, match="Box"):
        grid.shift_actions(np.zeros(1))
    grid.close()


def test_adopting_needs_variants():
    with pytest.raises(ValueError, match="pool variants"):
        LoopConfig(adopt_variants=True)
    assert RunConfig(loop=LoopConfig(adopt_variants=True, pool_variants=2)).loop.adopt_variants
