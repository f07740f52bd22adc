"""Sampling a round's behaviour pool from a policy (SPEC §3.1–3.2).

Episodes of the policy (with random exploration mixed in) are cut into non-overlapping
windows of L steps; of `oversample` × N windows (at most `max_windows`, never fewer than N:
`windows_to_sample`) the N the reward ensemble is most uncertain about are kept (a uniformly
random N without an ensemble). The episodes come from the round's pool sources
(`pool.sources`: the policy, and a share of them from its biased variants when asked). The
headless loop, the app and `groupwise pool` all sample through `sample_pool`.
"""

import dataclasses
import math
from collections.abc import Sequence
from typing import Literal

import numpy as np

from groupwise.behaviour.pool import BehaviourPool
from groupwise.clips.timing import clip_timing, step_seconds
from groupwise.episodes.fragments import (
    Trajectory,
    most_uncertain,
    stack_fragments,
    tile_fragments,
)
from groupwise.pool.sources import (
    CurrentPolicy,
    PoolSource,
    SourceContext,
    shifted_progress,
    split_windows,
)
from groupwise.query.groups import step_variance
from groupwise.reward import RewardEnsemble
from groupwise.rl.agents import Agent
from groupwise.rl.policy import Policy
from groupwise.rl.rollout import EnvFactory
from groupwise.types import IntArray, ProgressFn


def sample_pool(
    make_env: EnvFactory,
    policy: Policy,
    size: int,
    length: int,
    rng: np.random.Generator,
    *,
    round_index: int = 0,
    exploration_fraction: float = 0.0,
    oversample: float = 1.0,
    max_windows: int | None = None,
    ensemble: RewardEnsemble | None = None,
    select: Literal["uncertain", "random"] = "uncertain",
    progress: ProgressFn | None = None,
    snapshot_offsets: Sequence[int] | None = None,
    processes: int | None = None,
    sources: Sequence[PoolSource] | None = None,
    agent: Agent | None = None,
) -> BehaviourPool:
    """A pool of (up to) `size` behaviours of `length` steps (module docstring).

    With an `ensemble` the pool carries its predicted returns (N, K) and step variance, and
    keeps the windows it is most uncertain about (`select="random"`: a random subset);
    without one the predicted returns are an empty (N, 0) array. `progress` hears the
    steps sampled towards the windows (`rl.rollout.sample_episodes_for_windows`).
    `snapshot_offsets` are the steps into each window whose physics state the episodes keep
    (MuJoCo envs); by default those a window's clip and poster are rendered from
    (`ClipTiming.snapshot_offsets`: two states of a few hundred bytes a window), so a clip can
    be rendered on demand without replaying its episode (`clips.recipe`). `processes` step
    the episodes' envs (None: the free cores for large batches; `rl.batch_envs`): the pool is
    the same whatever it is.

    `sources` are where the episodes come from (`pool.sources`; default: `policy` alone with
    `exploration_fraction`, `CurrentPolicy`): each draws what it fixes for the round
    (`PoolSource.for_round`), then each samples its share of the windows (`split_windows`),
    in order, from `rng`; the episodes are numbered in that order and each knows its
    `Trajectory.source` (0 the policy, then the other sources' tags). `agent` is the learner
    `policy` is of, for a source that reads it (`SourceContext.agent`).

    Raises:
        ValueError: `size` < 1, `oversample` < 1 or `max_windows` < 1, sources whose shares
            do not add up (`pool.sources.split_windows`), both `sources` and a nonzero
            `exploration_fraction`, or episodes too short for a window.
    """
    if sources is not None and exploration_fraction:
        raise ValueError("give the exploration fraction to the sources, not beside them")
    composed: Sequence[PoolSource] = (
        (CurrentPolicy(exploration_fraction),) if sources is None else sources
    )
    n_windows = windows_to_sample(size, oversample, max_windows)
    if snapshot_offsets is None:
        probe = make_env()
        try:
            snapshot_offsets = clip_timing(step_seconds(probe), steps=length).snapshot_offsets
        finally:
            probe.close()
    ctx = SourceContext(
        make_env,
        policy,
        length,
        round_index,
        tuple(snapshot_offsets),
        processes,
        agent,
    )
    counts = split_windows(n_windows, composed)
    drawn = [source.for_round(ctx, rng) for source in composed]
    total = n_windows * length
    episodes: list[Trajectory] = []
    sampled = 0  # steps towards the windows of the sources before this one
    first_tag = 0  # the Trajectory.source of this source's first tag
    for source, count in zip(drawn, counts, strict=True):
        if count > 0:
            own = source.sample(
                ctx,
                count,
                rng,
                shifted_progress(progress, sampled, total),
            )
            episodes += [
                dataclasses.replace(e, episode=len(episodes) + i, source=first_tag + e.source)
                for i, e in enumerate(own)
            ]
        sampled += count * length
        first_tag += source.tags
    windows = tile_fragments(episodes, length)
    if ensemble is None:
        keep = _random_subset(len(windows), size, rng)
        kept = tuple(windows[i] for i in keep)
        return BehaviourPool(round_index, kept, np.zeros((len(kept), 0)), episodes=tuple(episodes))
    obs, acts = stack_fragments(windows)
    step = ensemble.step_rewards(obs, acts)  # (K, M, L): one forward pass for both uses
    returns = np.ascontiguousarray(step.sum(axis=-1).T)  # (M, K), as ensemble.returns
    if select == "random":
        keep = _random_subset(len(windows), size, rng)
    else:
        keep = most_uncertain(returns.var(axis=1), size)
    return BehaviourPool(
        round_index,
        tuple(windows[i] for i in keep),
        returns[keep],
        step_variance(step[:, keep]),
        episodes=tuple(episodes),
    )


def windows_to_sample(size: int, oversample: float, max_windows: int | None = None) -> int:
    """How many windows a pool of `size` behaviours is chosen from: ⌈`oversample` × size⌉,
    at most `max_windows` (None: no limit), and never fewer than `size`.

    Raises:
        ValueError: `size` < 1, `oversample` < 1 or `max_windows` < 1.
    """
    if size < 1 or oversample < 1.0 or (max_windows is not None and max_windows < 1):
        raise ValueError(
            f"need size >= 1, oversample >= 1 and max_windows >= 1, got {size}, {oversample} "
            f"and {max_windows}"
        )
    wanted = math.ceil(size * oversample)
    return wanted if max_windows is None else max(size, min(wanted, max_windows))


def _random_subset(n: int, size: int, rng: np.random.Generator) -> IntArray:
    """`size` of `n` indices, uniformly, in ascending order (all of them when n <= size)."""
    if n <= size:
        return np.arange(n)
    return np.sort(rng.choice(n, size=size, replace=False))
