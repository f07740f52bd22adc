"""PPO's own rollouts, recorded for the next round's pool (issue 39: fresh pools).

A pool sampled from a policy snapshot shows behaviour PPO has since moved on from (the app
showed pools 276,480 and 1,040,384 PPO steps old; QPA, Hu et al. ICLR 2024, calls this
query–policy misalignment and queries the policy's most recent episodes instead). So in
continuous training every env PPO steps is wrapped (`RecordingEnv`) and its episodes are
kept as they are collected: the observations before each step, the raw actions the env got
(SB3 clips Box actions before stepping), the true rewards, and, for MuJoCo envs, the physics
states a window's clip and poster are rendered from (`envs.physics_state`; the steps
`rl.rollout.sample_episodes_for_windows` captures for a sampled pool). Each episode is reset
with a seed of its own: the first of a `learn` call with the seed SB3 gives it, every later
one with a seed drawn from a generator seeded by that one, so every recorded window replays
from its reset as a sampled one does (`clips.replay`). A `RolloutRecorder` keeps the latest
episodes, finished or still running, as long as they hold `keep_windows` windows; a pool cut
from them costs no sampling (`pool.recent.RecentRollouts`).

The policy that played a step is PPO's as of the rollout it was collected in: its step count
then, a whole number of rollouts (`policy_steps`), so a behaviour's age is the PPO steps
between that policy and the one judging it.

Seeding every reset changes which initial states PPO's episodes start from (not their
distribution): a run with recording is a different run, seed for seed, from one without.
"""

import bisect
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3.common.vec_env import DummyVecEnv, VecEnv

from groupwise.envs.physics_state import physics_state
from groupwise.envs.spaces import encode_actions
from groupwise.envs.true_reward import TRUE_REWARD_KEY
from groupwise.episodes.fragments import Trajectory
from groupwise.types import FloatArray


@dataclass
class _Episode:
    """One episode being recorded."""

    reset_seed: int
    obs: list[np.ndarray] = field(default_factory=list)  # before each step, and the next
    actions: list[Any] = field(default_factory=list)
    rewards: list[float] = field(default_factory=list)
    policy_steps: list[int] = field(default_factory=list)  # the acting policy's, per step
    snapshots: dict[int, FloatArray] = field(default_factory=dict)

    def trajectory(
        self, space: gym.Space, steps: int, episode: int, tile_from: int = 0
    ) -> Trajectory:
        """Its first `steps` steps as a `Trajectory` numbered `episode`, its windows from
        step `tile_from` on."""
        raw = np.asarray(self.actions[:steps])
        return Trajectory(
            obs=np.asarray(self.obs[:steps]).reshape(steps, -1).astype(np.float32),
            acts=encode_actions(space, raw),
            actions=raw,
            true_rewards=np.asarray(self.rewards[:steps], dtype=np.float64),
            reset_seed=self.reset_seed,
            episode=episode,
            snapshots={t: s for t, s in self.snapshots.items() if t < steps},
            tile_from=tile_from,
        )


@dataclass(frozen=True)
class RecentEpisode:
    """A recorded episode (or the part of a running one recorded so far) and, per step, the
    PPO steps of the policy that played it (`policy_steps`, (T,))."""

    trajectory: Trajectory
    policy_steps: np.ndarray  # (T,) int64

    def window_policy(self, start: int) -> int:
        """PPO steps of the oldest policy that played the window starting at `start`."""
        return int(self.policy_steps[start])


class RolloutRecorder:
    """The latest episodes of the envs PPO steps (module docstring).

    `length` (L) and `snapshot_offsets` say which physics states to keep (before steps
    ``k·L + o − 1``); `keep_windows` how many whole windows the finished episodes kept must
    hold at least (older ones are dropped); `clock` is the agent's PPO step count and
    `rollout` its rollout size (n_envs × n_steps).
    """

    def __init__(
        self,
        space: gym.Space,
        length: int,
        snapshot_offsets: Sequence[int],
        keep_windows: int,
        clock: Callable[[], int],
        rollout: int,
    ) -> None:
        if length < 1 or keep_windows < 1 or rollout < 1:
            raise ValueError(
                f"need length, keep_windows and rollout >= 1, got {length}, {keep_windows} "
                f"and {rollout}"
            )
        self.space = space
        self.length = length
        self.offsets = tuple(snapshot_offsets)
        self.keep_windows = keep_windows
        self.clock = clock
        self.rollout = rollout
        self.running: dict[int, _Episode] = {}  # env index → its episode now
        self.finished: deque[tuple[_Episode, int]] = deque()  # (episode, steps), oldest first

    def policy_steps(self) -> int:
        """PPO steps of the policy acting now (the step count at its rollout's start)."""
        return self.clock() // self.rollout * self.rollout

    def wants_state(self, t: int) -> bool:
        """Whether the physics state before step `t` is kept (a window's clip or poster)."""
        return any(t + 1 - o >= 0 and (t + 1 - o) % self.length == 0 for o in self.offsets)

    def recent(self, windows: int, since: int = 0) -> list[RecentEpisode]:
        """The newest episodes holding at least `windows` whole windows played by policies
        of at least `since` PPO steps (all there are when fewer), oldest first: the running
        episodes' parts recorded so far, then the finished ones from the newest; numbered
        0 … E − 1 in the order returned. An episode an older policy began is returned whole
        (its reset replays it), its windows from the first window boundary at or after its
        first step played since (`Trajectory.tile_from`)."""
        chosen: list[tuple[_Episode, int, int]] = []
        held = 0
        running = [(e, len(e.actions)) for _, e in sorted(self.running.items())]
        for episode, steps in [*running, *reversed(self.finished)]:
            if held >= windows:
                break
            first = bisect.bisect_left(episode.policy_steps, since, hi=steps)
            start = -(-first // self.length) * self.length  # the next window boundary
            if steps - start >= self.length:
                chosen.append((episode, steps, start))
                held += (steps - start) // self.length
        chosen.reverse()
        return [
            RecentEpisode(
                e.trajectory(self.space, steps, i, start),
                np.asarray(e.policy_steps[:steps], np.int64),
            )
            for i, (e, steps, start) in enumerate(chosen)
        ]

    def clear(self) -> None:
        """Forget every episode recorded so far; an env's episode is recorded again from
        its next reset."""
        self.finished.clear()
        self.running.clear()

    def held_windows(self) -> int:
        """Whole windows the kept episodes hold now (running ones included)."""
        running = sum(len(e.actions) // self.length for e in self.running.values())
        return running + sum(steps // self.length for _, steps in self.finished)

    def _finish(self, index: int) -> None:
        episode = self.running.pop(index, None)
        if episode is None or not episode.actions:
            return
        self.finished.append((episode, len(episode.actions)))
        windows = sum(steps // self.length for _, steps in self.finished)
        while self.finished and windows - self.finished[0][1] // self.length >= self.keep_windows:
            windows -= self.finished.popleft()[1] // self.length


class RecordingEnv(gym.Wrapper[Any, Any, Any, Any]):
    """One of PPO's envs, its episodes recorded into `recorder` as env `index`."""

    def __init__(self, env: gym.Env[Any, Any], recorder: RolloutRecorder, index: int) -> None:
        super().__init__(env)
        self.recorder = recorder
        self.index = index
        self._seeds = np.random.default_rng(index)

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        if seed is None:
            seed = int(self._seeds.integers(2**31 - 1))
        else:  # a `learn` call's first reset: SB3's seed fixes the rest of its resets too
            self._seeds = np.random.default_rng(seed)
        self.recorder._finish(self.index)  # an episode cut short by a forced reset
        obs, info = self.env.reset(seed=seed, options=options)
        episode = self.recorder.running[self.index] = _Episode(reset_seed=seed)
        episode.obs.append(np.asarray(obs))
        return obs, info

    def step(self, action: Any) -> tuple[Any, Any, bool, bool, dict[str, Any]]:
        episode = self.recorder.running.get(self.index)
        if episode is None:  # recording began mid-episode: its reset seed is unknown
            return self.env.step(action)
        t = len(episode.actions)
        if self.recorder.wants_state(t) and (state := physics_state(self.env)) is not None:
            episode.snapshots[t] = state
        obs, reward, terminated, truncated, info = self.env.step(action)
        episode.actions.append(np.array(action, copy=True))
        episode.rewards.append(float(info.get(TRUE_REWARD_KEY, reward)))
        episode.policy_steps.append(self.recorder.policy_steps())
        if terminated or truncated:
            self.recorder._finish(self.index)
        else:
            episode.obs.append(np.asarray(obs))
        return obs, reward, terminated, truncated, info


def dummy_vec_env(venv: VecEnv) -> DummyVecEnv:
    """The `DummyVecEnv` at the bottom of an SB3 wrapper stack (`VecNormalize` → … →
    `DummyVecEnv`).

    Raises:
        TypeError: the stack does not end in a `DummyVecEnv` (e.g. subprocess envs, whose
            episodes this process cannot see).
    """
    inner: Any = venv
    while not isinstance(inner, DummyVecEnv):
        inner = getattr(inner, "venv", None)
        if inner is None:
            raise TypeError(f"{type(venv).__name__} has no DummyVecEnv to record")
    return inner


def recorder_of(venv: VecEnv) -> RolloutRecorder | None:
    """The recorder of PPO's envs `venv`, None when they are not recorded."""
    first = dummy_vec_env(venv).envs[0]
    return first.recorder if isinstance(first, RecordingEnv) else None


def record_rollouts(
    venv: VecEnv,
    length: int,
    snapshot_offsets: Sequence[int],
    keep_windows: int,
    clock: Callable[[], int],
    rollout: int,
) -> RolloutRecorder:
    """Record the episodes of PPO's envs `venv` from the next reset on (module docstring);
    their recorder, the one they already have when called again."""
    found = recorder_of(venv)
    if found is not None:
        return found
    envs = dummy_vec_env(venv).envs
    recorder = RolloutRecorder(
        envs[0].action_space, length, snapshot_offsets, keep_windows, clock, rollout
    )
    envs[:] = [RecordingEnv(env, recorder, i) for i, env in enumerate(envs)]
    return recorder


def recorder_of_agent(agent: object) -> RolloutRecorder | None:
    """The recorder of an agent's PPO envs (groupwise's `PPOAgent`, or an SB3 model's
    `get_env()`), None when they are not recorded or not this process's."""
    venv = getattr(agent, "venv", None)
    if venv is None:
        get_env = getattr(getattr(agent, "model", None), "get_env", None)
        venv = get_env() if callable(get_env) else None
    if not isinstance(venv, VecEnv):
        return None
    try:
        return recorder_of(venv)
    except TypeError:
        return None
