"""A pool source of recorded episodes: label a dataset instead of an agent's behaviours
(issue 42; `envs.datasets` reads Minari datasets and D4RL-style HDF5).

Each round draws its windows uniformly from every window of L steps the dataset's
episodes hold (each episode tiled from an offset drawn anew every round, so later rounds
see other cuts); `pool.sampling.sample_pool` then keeps the N of them the reward ensemble
is least sure of once it has been fitted, as for any source:

    pool = sample_pool(make_env, policy, size, length, rng,
                       sources=(RecordedEpisodes("minari:mujoco/hopper/expert-v0", "Hopper-v5"),))

A window becomes a `Trajectory` of its own L steps whose `reset_seed` is the index of its
first step in the dataset (its episodes' steps one after another, as D4RL's arrays hold
them) and whose snapshots are its physics states (`envs.datasets.RecordedStates`), so its
clip is drawn from them.
"""

from dataclasses import dataclass

import numpy as np

from groupwise.envs.datasets import (
    RecordedEpisode,
    RecordedStates,
    episode_states,
    open_dataset,
)
from groupwise.episodes.fragments import Trajectory
from groupwise.pool.sources import FixedSource, PoolSource, SourceContext
from groupwise.types import ProgressFn


@dataclass(frozen=True)
class RecordedEpisodes(FixedSource):
    """Windows of a recorded dataset (`reference`, `envs.datasets.open_dataset`) shown in
    env `env` (module docstring)."""

    reference: str
    env: str
    share: float | None = None
    tags: int = 1

    def sample(
        self,
        ctx: SourceContext,
        windows: int,
        rng: np.random.Generator,
        progress: ProgressFn | None = None,
    ) -> list[Trajectory]:
        """`windows` windows drawn uniformly from the dataset's (all of them when it holds
        fewer), in the dataset's order."""
        dataset = open_dataset(self.reference)
        length = ctx.length
        places = recorded_windows(dataset.episodes, length, rng)
        chosen = places if len(places) <= windows else places[_subset(len(places), windows, rng)]
        offsets = np.concatenate([[0], np.cumsum([len(e) for e in dataset.episodes])])
        trajectories = []
        states_of: dict[int, RecordedStates] = {}
        for episode_index, start in chosen.tolist():
            episode = dataset.episodes[episode_index]
            if episode_index not in states_of:
                states_of[episode_index] = episode_states(episode, self.env)
            trajectories.append(
                _window(episode, states_of[episode_index], start, length, offsets[episode_index])
            )
        if progress is not None:
            progress(windows * length, windows * length)
        return trajectories


def recorded_windows(
    episodes: tuple[RecordedEpisode, ...], length: int, rng: np.random.Generator
) -> np.ndarray:
    """Every window (episode, first step) (M, 2) of `length` steps of `episodes`, each episode
    tiled from an offset in [0, min(length, T − length + 1)) drawn from `rng`."""
    rows = []
    for index, episode in enumerate(episodes):
        spare = len(episode) - length
        if spare < 0:
            continue
        offset = int(rng.integers(min(length, spare + 1)))
        for start in range(offset, spare + 1, length):
            rows.append((index, start))
    return np.array(rows, dtype=np.int64).reshape(-1, 2)


def _subset(n: int, size: int, rng: np.random.Generator) -> np.ndarray:
    return np.sort(rng.choice(n, size=size, replace=False))


def _window(
    episode: RecordedEpisode, states: RecordedStates, start: int, length: int, first_step: int
) -> Trajectory:
    part = slice(start, start + length)
    return Trajectory(
        obs=episode.obs[part].astype(np.float32),
        acts=np.asarray(episode.actions[part], dtype=np.float32),
        actions=np.asarray(episode.actions[part]),
        true_rewards=episode.rewards[part],
        reset_seed=int(first_step) + start,
        episode=0,
        snapshots=RecordedStates(states.env, states.qpos[part], states.qvel[part]),
    )


def dataset_sources(reference: str, env: str) -> tuple[PoolSource, ...]:
    """The sources of a dataset session's pools: its recorded windows alone."""
    return (RecordedEpisodes(reference, env),)
