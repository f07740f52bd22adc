"""A pool source that reads PPO's own latest rollouts (issue 39: fresh pools).

In continuous training PPO plays thousands of episodes while a person compares; the next
round's pool is cut from the latest of them (`rl.recording`) when the round ends, so the
person judges what the agent does now and the pool costs no sampling. A round with fewer
recorded windows than it needs (round 0, or the first round after a worker restarted) samples
the rest from the policy as `CurrentPolicy` does.

    pool = sample_pool(..., sources=fresh_sources(loop), agent=run.agent)
    ages = pool_ages(pool, recorder_of_agent(run.agent), run.agent.num_timesteps)

The pool variants of a fresh pool (`FreshVariants`) are stepped side by side, one policy
call per step for all of them, since the person waits for them at End round.
"""

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from groupwise.behaviour.pool import BehaviourPool
from groupwise.config import LoopConfig
from groupwise.episodes.fragments import Trajectory
from groupwise.pool.sources import (
    FixedSource,
    PolicyVariants,
    PoolSource,
    SourceContext,
    pool_sources,
    sample_policy,
    shifted_progress,
)
from groupwise.rl.policy import BiasedPolicy
from groupwise.rl.recording import RolloutRecorder, recorder_of_agent
from groupwise.types import FloatArray, IntArray, ProgressFn


@dataclass(frozen=True)
class RecentRollouts(FixedSource):
    """The windows of the learner's latest recorded rollouts (`rl.recording.record_rollouts`
    on its envs) played by policies at most `max_age` rollouts older than the policy now,
    the rest sampled from the policy now with `exploration` random actions. Recorded
    episodes have no random actions: PPO's own stochastic policy played them.

    With the default 1 every behaviour of a pool cut between PPO updates is at most one
    rollout old (issue 39): the last rollout's windows, played by the policy just before
    the latest update, and the rest sampled from the policy as it is."""

    exploration: float = 0.0
    share: float | None = None
    tags: int = 1
    max_age: int = 1

    def sample(
        self,
        ctx: SourceContext,
        windows: int,
        rng: np.random.Generator,
        progress: ProgressFn | None = None,
    ) -> list[Trajectory]:
        recorder = None if ctx.agent is None else recorder_of_agent(ctx.agent)
        if recorder is None:
            recent = []
        else:
            since = recorder.policy_steps() - self.max_age * recorder.rollout
            recent = recorder.recent(windows, since)
        episodes = [e.trajectory for e in recent]
        held = sum(e.windows(ctx.length) for e in episodes)
        total = windows * ctx.length
        if progress is not None:
            progress(min(held, windows) * ctx.length, total)
        if held < windows:
            shifted = shifted_progress(progress, held * ctx.length, total)
            episodes += sample_policy(
                ctx, ctx.policy, windows - held, rng, self.exploration, shifted
            )
        return episodes


@dataclass(frozen=True)
class FreshVariants(PolicyVariants):
    """`PolicyVariants` stepped side by side: one batch of episodes for all the variants,
    episode e played by variant e mod `count` (`VariantRows`), so that the person waiting at
    End round waits for one policy call per step, not one per variant and step (issue 39:
    8 variants one after another took 6.3 s of a 10.4 s wait on Hopper). The windows are
    dealt over the variants in whole episodes (Hopper's 1,000 steps hold 5 windows of 188):
    no variant plays a part-used episode of its own, and a share of fewer episodes than
    variants shows only the first variants (the app's 100 behaviours of 188 steps: 20
    episodes for 8 variants; each round draws the variants anew)."""

    def for_round(self, ctx: SourceContext, rng: np.random.Generator) -> "FreshVariants":
        return replace(self, policies=super().for_round(ctx, rng).policies)

    def sample(
        self,
        ctx: SourceContext,
        windows: int,
        rng: np.random.Generator,
        progress: ProgressFn | None = None,
    ) -> list[Trajectory]:
        if len(self.policies) != self.count:
            raise ValueError("FreshVariants samples the variants for_round drew")
        rows = VariantRows(self.policies)
        episodes = sample_policy(ctx, rows, windows, rng, self.exploration, progress)
        return [replace(e, source=e.episode % self.count) for e in episodes]


class VariantRows:
    """Biased variants of one policy acting side by side (`rl.policy.RowPolicy`): episode e
    of a batch is variant e mod len(`variants`)'s; one call of their base policy a step."""

    def __init__(self, variants: Sequence[BiasedPolicy]) -> None:
        if not variants or any(v.base is not variants[0].base for v in variants):
            raise ValueError("VariantRows needs variants of one base policy")
        self.variants = tuple(variants)
        self.base = variants[0].base

    def act(self, obs: FloatArray, rng: np.random.Generator) -> np.ndarray:
        return self.act_rows(obs, np.arange(len(obs)), rng)

    def act_rows(self, obs: FloatArray, episodes: IntArray, rng: np.random.Generator) -> np.ndarray:
        actions = np.asarray(self.base.act(obs, rng))
        which = np.asarray(episodes) % len(self.variants)
        pushed: np.ndarray | None = None
        for k, variant in enumerate(self.variants):
            rows = np.flatnonzero(which == k)
            if len(rows):
                own = variant.push(actions[rows], rng)
                if pushed is None:
                    pushed = np.empty((len(actions), *own.shape[1:]), dtype=own.dtype)
                pushed[rows] = own
        assert pushed is not None  # every row is some variant's
        return pushed


def fresh_sources(loop: LoopConfig, kept: PoolSource | None = None) -> tuple[PoolSource, ...]:
    """`pool_sources(loop)` with the policy's place taken by its latest rollouts: the
    variants, when `loop` asks for them, still give their share, stepped side by side
    (`FreshVariants`); then `kept`'s share, when given (the kept policy's, `run.kept_policy`;
    its tag is `kept_tag(loop)`)."""
    _policy, *others = pool_sources(loop)
    fresh = [
        FreshVariants(o.count, o.share, o.scale, o.exploration)
        if isinstance(o, PolicyVariants)
        else o
        for o in others
    ]
    sources = (RecentRollouts(loop.exploration_fraction), *fresh)
    return sources if kept is None else (*sources, kept)


def kept_tag(loop: LoopConfig) -> int:
    """The `Trajectory.source` tag of the kept policy's share of a fresh pool
    (`run.kept_policy`)."""
    return sum(source.tags for source in fresh_sources(loop))


def pool_ages(
    pool: BehaviourPool,
    recorder: RolloutRecorder | None,
    now: int,
    sampled: Mapping[int, int] | None = None,
) -> IntArray:
    """Each behaviour's age (N,): the PPO steps from the policy that played its window's
    first step to the agent's step count `now`; for a window sampled (not recorded), 0, or
    `now` − `sampled[tag]` when an older policy of steps `sampled[tag]` played its episodes
    of that `Trajectory.source` tag (the kept policy's share). Call it as the pool is cut:
    the recorder drops old episodes."""
    sampled = {} if sampled is None else sampled
    tags: list[int] = [-1] * len(pool) if pool.sources is None else pool.sources.tolist()
    played: dict[int, np.ndarray] = {}
    if recorder is not None:
        for episode in recorder.recent(recorder.held_windows()):
            played[episode.trajectory.reset_seed] = episode.policy_steps
    ages = np.zeros(len(pool.fragments), dtype=np.int64)
    for i, fragment in enumerate(pool.fragments):
        steps = played.get(fragment.reset_seed)
        if tags[i] in sampled:
            ages[i] = now - sampled[tags[i]]
        elif steps is not None and fragment.start < len(steps):
            ages[i] = now - int(steps[fragment.start])
    return ages
