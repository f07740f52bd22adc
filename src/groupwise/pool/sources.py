"""Where a round's behaviours come from: the pool sources a round composes (issue 38).

A pool is cut from episodes (trajectories) played by one or more sources. A source is a
small object with two verbs; the round builds its list once (`pool_sources`, from the
config) and `pool.sampling.sample_pool` asks each in turn, as Stable-Baselines3 runs a
list of callbacks or imitation wraps a fragmenter, so that adding a source adds an object,
not an `if cfg.flag:` inside `begin_round`:

    sources = pool_sources(cfg.loop)           # CurrentPolicy, then PolicyVariants if asked
    pool = sample_pool(make_env, policy, size, length, rng, sources=sources, agent=agent)

The sources that measured a gain (docs/case-studies.md): the current policy with its random
exploration (`CurrentPolicy`, SPEC §3.1) and biased variants of it (`PolicyVariants`,
issue 20). A source that reads the learner's own latest rollouts fits the same protocol: it
finds them through `SourceContext.agent` and returns them from `sample`.
"""

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Protocol, Self

import gymnasium as gym
import numpy as np

from groupwise.config import LoopConfig
from groupwise.episodes.fragments import Trajectory
from groupwise.rl.agents import Agent
from groupwise.rl.policy import BiasedPolicy, Policy, biased_variants
from groupwise.rl.rollout import EnvFactory, sample_episodes_for_windows
from groupwise.types import ProgressFn


@dataclass(frozen=True)
class SourceContext:
    """What a round gives every source: where and what it samples."""

    make_env: EnvFactory
    """A fresh env of the run (sampling never steps PPO's own envs)."""
    policy: Policy
    """The round's current (stochastic) policy."""
    length: int
    """L, steps per window (behaviour)."""
    round_index: int
    snapshot_offsets: tuple[int, ...] = ()
    """Steps into each window whose physics state the episodes keep (`Trajectory.snapshots`)."""
    processes: int | None = None
    """Processes stepping the envs (`rl.batch_envs`; None: the free cores for large batches)."""
    agent: Agent | None = None
    """The learner `policy` is of, when the caller has one (a run's agent; None for a bare
    policy): a source that reads the learner's own rollouts needs it."""


class PoolSource(Protocol):
    """One place a round's behaviours come from.

    A round first calls `for_round` on every source, in order, then `sample` on what they
    returned, in the same order, all from the round's one sample stream `rng`; the pool's
    windows are tiled from the episodes in that order. Of the pool's n windows a source
    with a `share` gives round(share × n); the one source with `share` None (the policy)
    gives the rest.
    """

    @property
    def share(self) -> float | None:
        """The share of the pool's windows this source gives, in [0, 1]; None: what the
        other sources leave (exactly one source of a pool has None)."""
        ...

    @property
    def tags(self) -> int:
        """How many `Trajectory.source` tags its episodes use (0 … tags − 1); the pool
        numbers each source's tags after those of the sources before it (0: the policy,
        k: its k-th variant)."""
        ...

    def for_round(self, ctx: SourceContext, rng: np.random.Generator) -> "PoolSource":
        """The source as this round samples it, drawing from `rng` what it fixes for the
        whole round (the variants' biases); a source without such draws returns itself."""
        ...

    def sample(
        self,
        ctx: SourceContext,
        windows: int,
        rng: np.random.Generator,
        progress: ProgressFn | None = None,
    ) -> list[Trajectory]:
        """Episodes for `windows` windows of `ctx.length` steps (`windows` ≥ 1: a sampling
        source plays until they hold at least that many; a source of recorded episodes
        returns what it has, the pool tiles them all), each tagged with its local
        `Trajectory.source` in [0, `tags`); the pool renumbers their `episode`. `progress`
        hears (steps sampled towards the windows, `windows` × `ctx.length`)."""
        ...


class FixedSource:
    """A source that draws nothing for the whole round: `for_round` returns it as it is
    (a base for sources such as `CurrentPolicy`, `pool.recent.RecentRollouts`)."""

    def for_round(self, ctx: SourceContext, rng: np.random.Generator) -> Self:
        return self


@dataclass(frozen=True)
class CurrentPolicy(FixedSource):
    """The round's policy, with random actions on a share `exploration` of the steps in
    stretches (`rl.rollout.exploration_mask`; SPEC §3.1): the pool's own source. With a
    `policy`, that one instead, for a `share` of the pool (the kept policy's beside a fresh
    pool, `run.kept_policy`)."""

    exploration: float = 0.0
    share: float | None = None
    tags: int = 1
    policy: Policy | None = None

    def sample(
        self,
        ctx: SourceContext,
        windows: int,
        rng: np.random.Generator,
        progress: ProgressFn | None = None,
    ) -> list[Trajectory]:
        policy = ctx.policy if self.policy is None else self.policy
        return sample_policy(ctx, policy, windows, rng, self.exploration, progress)


@dataclass(frozen=True)
class PolicyVariants:
    """`count` biased variants of the round's policy (`rl.policy.biased_variants`: each
    pushes the actions one fixed way, by up to `scale` of half the action range, drawn
    anew every round), giving a share `share` of the windows, dealt evenly over them (the
    first ones get one more), so that the pool shows behaviours the policy itself rarely
    reaches (issue 20; `LoopConfig.pool_variants`). Episode tags 0 … count − 1 are the
    variants in order. `policies` are the round's variants (`for_round`); empty before."""

    count: int
    share: float = 0.5
    scale: float = 0.5
    exploration: float = 0.0
    policies: tuple[BiasedPolicy, ...] = ()

    def __post_init__(self) -> None:
        if self.count < 1 or not 0.0 <= self.share <= 1.0 or not 0.0 <= self.scale <= 1.0:
            raise ValueError(
                f"need count >= 1, share and scale in [0, 1], got {self.count}, {self.share} "
                f"and {self.scale}"
            )

    @property
    def tags(self) -> int:
        return self.count

    def for_round(self, ctx: SourceContext, rng: np.random.Generator) -> "PolicyVariants":
        probe = ctx.make_env()
        try:
            space: gym.Space = probe.action_space
        finally:
            probe.close()
        drawn = biased_variants(ctx.policy, space, self.count, self.scale, rng)
        return PolicyVariants(self.count, self.share, self.scale, self.exploration, tuple(drawn))

    def sample(
        self,
        ctx: SourceContext,
        windows: int,
        rng: np.random.Generator,
        progress: ProgressFn | None = None,
    ) -> list[Trajectory]:
        if len(self.policies) != self.count:
            raise ValueError("PolicyVariants samples the variants for_round drew")
        each, extra = divmod(windows, self.count)
        episodes: list[Trajectory] = []
        done = 0
        for tag, variant in enumerate(self.policies):
            count = each + (tag < extra)
            if count == 0:
                continue
            shifted = shifted_progress(progress, done, windows * ctx.length)
            own = sample_policy(ctx, variant, count, rng, self.exploration, shifted)
            episodes += [_tagged(e, tag) for e in own]
            done += count * ctx.length
        return episodes


def pool_sources(loop: LoopConfig) -> tuple[PoolSource, ...]:
    """The sources a round of `loop` samples its pool from: the current policy with
    `loop.exploration_fraction`, then `loop.pool_variants` variants of it when asked."""
    sources: list[PoolSource] = [CurrentPolicy(loop.exploration_fraction)]
    if loop.pool_variants:
        sources.append(
            PolicyVariants(
                loop.pool_variants,
                loop.pool_variant_share,
                loop.pool_variant_scale,
                loop.exploration_fraction,
            )
        )
    return tuple(sources)


def split_windows(n_windows: int, sources: Sequence[PoolSource]) -> list[int]:
    """How many of `n_windows` windows each of `sources` gives: round(share × n_windows) for
    a source with a share, the rest for the one without.

    Raises:
        ValueError: a negative count, not exactly one source without a share, a share
            outside [0, 1], or shares that together ask for more than `n_windows`.
    """
    rest = [i for i, source in enumerate(sources) if source.share is None]
    if n_windows < 0 or len(rest) != 1:
        raise ValueError(
            f"need n_windows >= 0 and exactly one source without a share, got {n_windows} "
            f"and {len(rest)}"
        )
    counts = [0 if s.share is None else _shared(n_windows, s.share) for s in sources]
    if sum(counts) > n_windows:
        raise ValueError(f"the sources' shares ask for {sum(counts)} of {n_windows} windows")
    counts[rest[0]] = n_windows - sum(counts)
    return counts


def _shared(n_windows: int, share: float) -> int:
    if not 0.0 <= share <= 1.0:
        raise ValueError(f"a source's share must be in [0, 1], got {share}")
    return round(share * n_windows)


def _tagged(episode: Trajectory, tag: int) -> Trajectory:
    return replace(episode, source=tag)


def sample_policy(
    ctx: SourceContext,
    policy: Policy,
    windows: int,
    rng: np.random.Generator,
    exploration: float,
    progress: ProgressFn | None,
) -> list[Trajectory]:
    """Episodes of `policy` for `windows` windows of `ctx.length` steps, with `exploration`
    random actions, sampled where and as `ctx` says (`rl.rollout.sample_episodes_for_windows`)."""
    return sample_episodes_for_windows(
        ctx.make_env,
        policy,
        windows,
        ctx.length,
        rng,
        exploration,
        progress=progress,
        snapshot_offsets=ctx.snapshot_offsets,
        processes=ctx.processes,
    )


def shifted_progress(progress: ProgressFn | None, before: int, total: int) -> ProgressFn | None:
    """`progress` hearing one part's steps as steps `before` + done of a whole of `total`
    (None when `progress` is None)."""
    if progress is None:
        return None
    return lambda done, _: progress(before + done, total)
