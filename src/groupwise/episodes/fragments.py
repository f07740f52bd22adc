"""Trajectories and the fixed-length fragments (behaviours) cut from them.

A fragment is exactly the window of L steps that one clip shows and one reward-model
input covers (SPEC §1, §3.2): the prototype's clips were not aligned with the labelled
window, which we do not repeat.
"""

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from groupwise.types import FloatArray, IntArray


@dataclass(frozen=True)
class Trajectory:
    """One whole episode, from reset to its own end (time limit, termination or a step cap).

    `reset_seed` reproduces the episode: reset the env with it and replay `actions`
    (the raw env actions) to re-render any window of it.
    """

    obs: FloatArray  # (T, obs_dim) observation before each step
    acts: FloatArray  # (T, act_dim) encoded action taken (one-hot for Discrete)
    actions: np.ndarray  # (T, *action_shape) raw env actions, for replay
    true_rewards: FloatArray  # (T,) the env's own reward (zeros for reward-free envs)
    reset_seed: int
    episode: int
    episode_score: float = math.nan
    """The env's score of the whole episode where it reports one: a target env's
    ``info["target_total"]`` at the last step, in the target's unit (not the sum of the
    per-step `true_rewards`); nan for other envs."""
    snapshots: Mapping[int, FloatArray] = field(default_factory=dict, compare=False, repr=False)
    """Step t → the physics state (S,) before step t, for the steps the sampler was asked to
    capture (MuJoCo envs only, `envs.physics_state`): a window's frames are rendered from
    there instead of replaying the episode from its reset (`clips.recipe`)."""
    source: int = 0
    """Which policy played it in a pool: 0 the round's policy, k its k-th variant
    (`groupwise.pool.sampling.sample_pool`)."""
    tile_from: int = 0
    """The step its windows start at or after (`tile_fragments`), a multiple of the window
    length: the steps before it are kept to replay the episode from its reset, not shown
    (a recorded episode whose early steps an older policy played, `pool.recent`)."""

    def __post_init__(self) -> None:
        t = self.obs.shape[0]
        if not (self.acts.shape[0] == self.true_rewards.shape[0] == len(self.actions) == t):
            raise ValueError(
                f"trajectory arrays disagree on length: obs {self.obs.shape}, "
                f"acts {self.acts.shape}, rewards {self.true_rewards.shape}"
            )

    def __len__(self) -> int:
        return int(self.obs.shape[0])

    def windows(self, length: int) -> int:
        """How many windows of `length` steps `tile_fragments` cuts from it."""
        return max(0, (len(self) - self.tile_from) // length)


@dataclass(frozen=True)
class Fragment:
    """L consecutive steps of one trajectory: the unit the user judges."""

    obs: FloatArray  # (L, obs_dim)
    acts: FloatArray  # (L, act_dim) encoded actions
    true_rewards: FloatArray  # (L,)
    episode: int
    start: int  # index of the first step within the episode
    reset_seed: int

    @property
    def length(self) -> int:
        return int(self.obs.shape[0])

    @property
    def true_return(self) -> float:
        return float(self.true_rewards.sum())

    @property
    def key(self) -> str:
        """Identifier unique within one pool (episode and start step)."""
        return f"e{self.episode}-s{self.start}"


def tile_fragments(trajectories: Sequence[Trajectory], length: int) -> list[Fragment]:
    """Cut every trajectory into consecutive, non-overlapping windows of `length` steps.

    Each trajectory is tiled on its own from its `Trajectory.tile_from` step (0 but for a
    recorded episode partly played by an older policy), `Trajectory.windows` windows, so no
    window crosses an episode's end. A trailing remainder shorter than `length` is dropped (a
    trajectory shorter than `length` gives none), so every fragment has exactly one clip of
    exactly `length` frames.
    """
    if length < 1:
        raise ValueError(f"fragment length must be >= 1, got {length}")
    fragments = []
    for traj in trajectories:
        for start in range(traj.tile_from, len(traj) - length + 1, length):
            window = slice(start, start + length)
            fragments.append(
                Fragment(
                    obs=traj.obs[window],
                    acts=traj.acts[window],
                    true_rewards=traj.true_rewards[window],
                    episode=traj.episode,
                    start=start,
                    reset_seed=traj.reset_seed,
                )
            )
    return fragments


def stack_fragments(fragments: Sequence[Fragment]) -> tuple[FloatArray, FloatArray]:
    """Stack equal-length fragments into (N, L, obs_dim) and (N, L, act_dim) arrays."""
    if not fragments:
        raise ValueError("no fragments to stack")
    obs = np.stack([f.obs for f in fragments]).astype(np.float32)
    acts = np.stack([f.acts for f in fragments]).astype(np.float32)
    return obs, acts


def most_uncertain(uncertainty: FloatArray, n: int) -> IntArray:
    """Indices of the `n` highest `uncertainty` scores (N,), in ascending index order.

    With n >= N every index is kept. Ties keep the earlier fragment.
    """
    uncertainty = np.asarray(uncertainty)
    if n >= len(uncertainty):
        return np.arange(len(uncertainty))
    return np.sort(np.argsort(-uncertainty, kind="stable")[: max(n, 0)])
