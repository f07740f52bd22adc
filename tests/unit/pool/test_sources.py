"""The pool sources a round composes (`pool.sources`): how they share the windows, what the
config builds, and that a source of ready-made episodes fits beside the policy."""

from dataclasses import dataclass, replace

import numpy as np
import pytest

from groupwise.config import LoopConfig
from groupwise.envs import make_env
from groupwise.episodes.fragments import Trajectory
from groupwise.pool.sampling import sample_pool
from groupwise.pool.sources import (
    CurrentPolicy,
    PolicyVariants,
    PoolSource,
    SourceContext,
    pool_sources,
    split_windows,
)
from groupwise.rl.policy import RandomPolicy
from groupwise.rl.rollout import sample_episodes_for_windows


def _grid():
    return make_env("GridWorld")


def test_split_windows_gives_each_share_and_the_rest_to_the_policy():
    policy, variants = CurrentPolicy(), PolicyVariants(8, 0.5)
    assert split_windows(100, [policy]) == [100]
    assert split_windows(100, [policy, variants]) == [50, 50]
    assert split_windows(10, [policy, PolicyVariants(3, 1.0)]) == [0, 10]
    assert split_windows(7, [PolicyVariants(2, 0.25), policy]) == [2, 5]  # round(1.75)
    with pytest.raises(ValueError, match="exactly one source without a share"):
        split_windows(10, [variants])
    with pytest.raises(ValueError, match="ask for 12 of 10"):
        split_windows(10, [policy, PolicyVariants(2, 0.6), PolicyVariants(2, 0.6)])


def test_the_config_composes_the_policy_and_its_variants():
    assert pool_sources(LoopConfig(exploration_fraction=0.25)) == (CurrentPolicy(0.25),)
    loop = LoopConfig(pool_variants=4, pool_variant_share=0.3, pool_variant_scale=0.2)
    assert pool_sources(loop) == (
        CurrentPolicy(0.05),
        PolicyVariants(4, share=0.3, scale=0.2, exploration=0.05),
    )
    with pytest.raises(ValueError, match="need count >= 1"):
        PolicyVariants(0)


def test_variants_are_drawn_for_the_round_and_deal_their_windows_evenly():
    ctx = SourceContext(_grid, RandomPolicy(_grid().action_space), length=5, round_index=0)
    source = PolicyVariants(3, scale=1.0)
    with pytest.raises(ValueError, match="for_round"):
        source.sample(ctx, 6, np.random.default_rng(0))
    drawn = source.for_round(ctx, np.random.default_rng(0))
    again = source.for_round(ctx, np.random.default_rng(0))
    assert len(drawn.policies) == 3 and source.policies == ()  # the source itself is unchanged
    assert [p.action for p in drawn.policies] == [p.action for p in again.policies]
    episodes = drawn.sample(ctx, 7, np.random.default_rng(1))  # 3 + 2 + 2 windows
    assert sorted({e.source for e in episodes}) == [0, 1, 2]


@dataclass(frozen=True)
class Replayed:
    """A source of episodes sampled before the round (as PPO's own latest rollouts would be)."""

    episodes: tuple[Trajectory, ...]
    share: float | None = 0.5
    tags: int = 1

    def for_round(self, ctx: SourceContext, rng: np.random.Generator) -> "Replayed":
        return self

    def sample(self, ctx, windows, rng, progress=None) -> list[Trajectory]:
        return [replace(e, source=0) for e in self.episodes]


def test_a_source_of_ready_made_episodes_fits_beside_the_policy():
    policy = RandomPolicy(_grid().action_space)
    old = sample_episodes_for_windows(_grid, policy, 4, 5, np.random.default_rng(3))
    sources: list[PoolSource] = [
        CurrentPolicy(),
        PolicyVariants(2, 0.25),
        Replayed(tuple(old), 0.25),
    ]
    pool = sample_pool(_grid, policy, 12, 5, np.random.default_rng(0), sources=sources)
    tags = [e.source for e in pool.episodes]
    assert tags[0] == 0 and tags[-len(old) :] == [3] * len(old)  # after the variants' 1, 2
    assert [e.episode for e in pool.episodes] == list(range(len(pool.episodes)))
    np.testing.assert_array_equal(pool.episodes[-1].obs, old[-1].obs)
    with pytest.raises(ValueError, match="to the sources"):
        sample_pool(_grid, policy, 4, 5, np.random.default_rng(0), sources=sources,
                    exploration_fraction=0.1)  # fmt: skip
