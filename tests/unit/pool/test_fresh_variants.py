"""A fresh pool's variants are stepped side by side (`pool.recent.FreshVariants`, issue 39):
one batch, episode e played by variant e mod count, each step's actions its variant's push of
the one base policy's, dealt in whole episodes; the round's share of windows kept."""

import numpy as np
import pytest

from groupwise.config import LoopConfig
from groupwise.envs import make_env
from groupwise.pool.recent import FreshVariants, RecentRollouts, VariantRows, fresh_sources
from groupwise.pool.sampling import sample_pool
from groupwise.pool.sources import PolicyVariants, SourceContext
from groupwise.rl.policy import BiasedPolicy, RandomPolicy

ENV = "MountainCarContinuous"  # a Box action, 250 steps an episode


def _env():
    return make_env(ENV)


class Still:
    """A base policy that always pushes with 0.1: each variant's actions are its own."""

    def act(self, obs, rng):
        return np.full((len(obs), 1), 0.1, dtype=np.float32)


def test_variants_side_by_side_play_their_own_episodes():
    ctx = SourceContext(_env, Still(), length=50, round_index=0)
    source = FreshVariants(3, scale=1.0).for_round(ctx, np.random.default_rng(0))
    assert isinstance(source, FreshVariants) and len(source.policies) == 3
    episodes = source.sample(ctx, 12, np.random.default_rng(1))  # 5 windows an episode
    assert len(episodes) == 3 and sum(len(e) // 50 for e in episodes) >= 12
    for episode in episodes:
        variant = source.policies[episode.episode % 3]
        assert episode.source == episode.episode % 3
        expected = variant.push(np.full((1, 1), 0.1, dtype=np.float32), np.random.default_rng())
        assert np.array_equal(episode.actions, np.repeat(expected, len(episode), axis=0))
    again = source.sample(ctx, 12, np.random.default_rng(1))
    assert all(np.array_equal(a.obs, b.obs) for a, b in zip(episodes, again, strict=True))


def test_rows_act_as_their_variants():
    space = _env().action_space
    base = RandomPolicy(space)
    variants = [BiasedPolicy(base, space, offset=np.array([o])) for o in (-0.5, 0.0, 0.5)]
    rows = VariantRows(variants)
    obs = np.zeros((4, 2), dtype=np.float32)
    drawn = base.act(obs, np.random.default_rng(2))
    acted = rows.act_rows(obs, np.array([3, 4, 5, 6]), np.random.default_rng(2))
    for row, episode in enumerate((3, 4, 5, 6)):
        pushed = variants[episode % 3].push(drawn[row : row + 1], np.random.default_rng())
        assert np.array_equal(acted[row], pushed[0])
    with pytest.raises(ValueError, match="one base policy"):
        VariantRows([variants[0], BiasedPolicy(RandomPolicy(space), space, offset=np.ones(1))])


def test_a_fresh_pool_keeps_the_variants_share():
    loop = LoopConfig(env=ENV, pool_variants=4)
    sources = fresh_sources(loop)
    assert [type(s) for s in sources] == [RecentRollouts, FreshVariants]
    assert isinstance(sources[1], PolicyVariants) and sources[1].count == 4
    pool = sample_pool(
        _env, RandomPolicy(_env().action_space), 20, 50, np.random.default_rng(3),
        oversample=1.0, sources=sources,
    )  # fmt: skip
    from_variants = [f for f in pool.fragments if pool.episodes[f.episode].source >= 1]
    assert len(from_variants) == round(loop.pool_variant_share * 20)
    # 10 windows are 2 episodes of 5: the first two variants' (a pool of 20 shows 2 of 4)
    assert {pool.episodes[f.episode].source for f in from_variants} == {1, 2}
