"""Reproducing a behaviour's frames: replay its episode in a rendering env.

A clip shows exactly its fragment's L steps, a frame every k-th step (`clips.timing`: k so
that the clip plays at real speed; k = 1 in envs of 30 steps a second or fewer): frame j
shows the state that step ``start + j·k``'s observation came from (the state before that
step's action), so the clip and the reward model's input are the same window (SPEC §1; the
prototype's were not).
Frames are reproduced, not recorded: reset a rendering env with the episode's `reset_seed`
and replay the episode's raw actions, stepping without rendering outside the windows. While
replaying, every observation is compared with the stored one, so a clip that would show
anything other than its fragment is never made (`ReplayMismatchError`).

A reset with a seed restores everything a frame depends on, so one rendering env can replay
any number of episodes in any order with the same frames (tested). Episodes may differ in
length (envs that terminate); `episode_arrays` stores the raw actions of episodes of any
lengths in one file and `episode_actions` gives one episode's back.
"""

import time
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import mujoco
import numpy as np
from gymnasium.envs.mujoco.mujoco_env import MujocoEnv

from groupwise.clips.video import VideoConfig
from groupwise.envs import make_env
from groupwise.envs.rendering import DEFAULT_FRAME_SIZE, FrameSize
from groupwise.episodes.fragments import Trajectory

PLANE_GRID_CELLS = 40
"""Most rendering-grid cells a side of a plane in clip frames (see `apply_clip_quality`)."""

CLIP_QUALITY: tuple[int, int, int] = (12, 6, 4)
"""MuJoCo (numslices, numstacks, numquads) for clip frames; MuJoCo's defaults are (28, 16, 4)."""

OBS_TOLERANCE = 1e-5
"""Relative and absolute tolerance of the replay check (observations are stored as float32)."""


class ReplayMismatchError(RuntimeError):
    """Replaying an episode's actions from its reset seed did not reproduce its observations."""


@dataclass(frozen=True)
class FrameSettings:
    """What a rendering env is made with and how its frames are encoded."""

    env: str
    """Short name (see `groupwise.envs.ENVS`) or Gymnasium id."""
    width: int = DEFAULT_FRAME_SIZE[0]
    height: int = DEFAULT_FRAME_SIZE[1]
    video: VideoConfig = field(default_factory=VideoConfig)


def make_render_env(settings: FrameSettings) -> gym.Env[Any, Any]:
    """A fresh env that renders `rgb_array` frames of the requested size.

    Gymnasium ids whose constructor takes no width/height (classic control: Pendulum-v1
    draws 500 × 500) are made at their own size and their frames scaled to fit the requested
    size, keeping their aspect (`envs.rendering.FrameSize`).

    Raises:
        RenderingUnavailableError: no offscreen GL backend (names the system packages).
        ValueError: unknown env.
    """
    try:
        env = make_env(
            settings.env, render_mode="rgb_array", width=settings.width, height=settings.height
        )
    except TypeError:
        env = FrameSize(
            make_env(settings.env, render_mode="rgb_array"), settings.width, settings.height
        )
    base = env.unwrapped
    if isinstance(base, MujocoEnv):
        apply_clip_quality(base.model)
    return env


def apply_clip_quality(model: mujoco.MjModel) -> None:
    """Cheaper geometry for clip frames, identical to the eye (and to ±1 intensity level).

    Must run before the env's first frame (MuJoCo builds its geometry when it creates the GL
    context). Two changes, neither touching the physics:

    - a plane is drawn as a grid of quads whose spacing is its third size; Hopper's floor
      (20 × 20 m, spacing 0.125) is 102,400 quads, which made llvmpipe spend two thirds of a
      frame on the floor. Planes get at most `PLANE_GRID_CELLS` cells a side (Hopper: 6.2 →
      1.9 ms a frame at 240×240; lighting is per pixel, so the frame does not change);
    - capsules, cylinders and spheres get MuJoCo's coarser `CLIP_QUALITY` tessellation.
    """
    quality = model.vis.quality
    quality.numslices, quality.numstacks, quality.numquads = CLIP_QUALITY
    planes = np.flatnonzero(model.geom_type == mujoco.mjtGeom.mjGEOM_PLANE)
    for g in planes:
        extent = 2.0 * float(max(model.geom_size[g, 0], model.geom_size[g, 1]))
        if model.geom_size[g, 2] > 0:
            model.geom_size[g, 2] = max(model.geom_size[g, 2], extent / PLANE_GRID_CELLS)


def replay_windows(
    env: gym.Env[Any, Any],
    reset_seed: int,
    actions: np.ndarray,
    starts: Sequence[int],
    length: int,
    observations: np.ndarray | None = None,
    timings: dict[str, float] | None = None,
    stride: int = 1,
) -> Iterator[tuple[int, np.ndarray]]:
    """Replay an episode and yield (start, frames (⌈length / stride⌉, H, W, 3) uint8) per
    window: frame j shows the state before step ``start + j·stride``.

    `starts` ascending; `actions` must reach the last window's last step (index
    ``starts[-1] + length - 2``). Every step is replayed, only the frames are strided. With
    `observations` (T + 1, obs_dim) every observation of the replay, up to the last window's
    end, is checked against the stored one. `timings` (optional) accumulates "replay_s" and
    "render_s".

    Raises:
        ReplayMismatchError: an observation differs from the stored one.
        ValueError: `starts` not ascending, the actions do not reach the last window, or
            `stride` < 1.
    """
    if list(starts) != sorted(starts) or len(set(starts)) != len(starts):
        raise ValueError(f"window starts must be ascending and distinct, got {list(starts)}")
    if stride < 1:
        raise ValueError(f"stride must be >= 1, got {stride}")
    if not starts:
        return
    end = starts[-1] + length  # exclusive: states 0 … end - 1 are checked
    if len(actions) < end - 1:
        raise ValueError(f"{len(actions)} actions do not reach step {end - 1}")
    clock = timings if timings is not None else {}
    clock.setdefault("replay_s", 0.0)
    clock.setdefault("render_s", 0.0)
    count = -(-length // stride)  # frames per window
    wanted: dict[int, list[tuple[int, int]]] = {}  # step → (window start, frame index)
    for s in starts:
        for j in range(count):
            wanted.setdefault(s + j * stride, []).append((s, j))
    frames: dict[int, np.ndarray] = {}
    tick = time.perf_counter()
    obs, _ = env.reset(seed=int(reset_seed))
    for t in range(end):
        if observations is not None:
            check_observation(obs, observations[t], t, reset_seed)
        if t in wanted:
            now = time.perf_counter()
            clock["replay_s"] += now - tick
            frame = np.asarray(env.render())
            tick = time.perf_counter()
            clock["render_s"] += tick - now
            for start, j in wanted[t]:
                if j == 0:
                    frames[start] = np.empty((count, *frame.shape), dtype=np.uint8)
                frames[start][j] = frame
                if j == count - 1:
                    clock["replay_s"] += time.perf_counter() - tick
                    yield start, frames.pop(start)
                    tick = time.perf_counter()
        if t + 1 < end:
            obs = env.step(actions[t])[0]
    clock["replay_s"] += time.perf_counter() - tick


def episode_arrays(trajectories: Sequence[Trajectory]) -> dict[str, np.ndarray]:
    """What replaying any window of `trajectories` needs, as arrays for one ``.npz`` file.

    ``episode``, ``reset_seed`` and ``length`` (E,) (steps of each episode) and ``actions``
    (E, T_max, *action_shape): each episode's raw actions, zero-padded after its length.

    Raises:
        ValueError: no trajectories.
    """
    if not trajectories:
        raise ValueError("no episodes to store")
    lengths = np.array([len(t) for t in trajectories], dtype=np.int64)
    first = np.asarray(trajectories[0].actions)
    actions = np.zeros((len(trajectories), int(lengths.max()), *first.shape[1:]), first.dtype)
    for row, t in enumerate(trajectories):
        actions[row, : len(t)] = t.actions
    return {
        "episode": np.array([t.episode for t in trajectories], dtype=np.int64),
        "reset_seed": np.array([t.reset_seed for t in trajectories], dtype=np.int64),
        "length": lengths,
        "actions": actions,
    }


def episode_actions(arrays: Mapping[str, np.ndarray], episode: int) -> np.ndarray:
    """Episode `episode`'s raw actions (T, *action_shape) from `episode_arrays`' arrays (or
    an ``np.load`` of their file); arrays without ``length`` are read as unpadded.

    Raises:
        KeyError: no such episode.
    """
    rows = np.flatnonzero(np.asarray(arrays["episode"]) == episode)
    if len(rows) == 0:
        raise KeyError(f"no episode {episode} among the stored episodes")
    row = int(rows[0])
    actions = np.asarray(arrays["actions"][row])
    if "length" in arrays:
        actions = actions[: int(arrays["length"][row])]
    return actions


def check_observation(obs: Any, stored: np.ndarray, t: int, reset_seed: int) -> None:
    """Raise `ReplayMismatchError` unless `obs` is the stored observation of step `t` (within
    `OBS_TOLERANCE`)."""
    replayed = np.asarray(obs, dtype=np.float32).reshape(-1)
    expected = np.asarray(stored, dtype=np.float32).reshape(-1)
    if replayed.shape != expected.shape or not np.allclose(
        replayed, expected, rtol=OBS_TOLERANCE, atol=OBS_TOLERANCE
    ):
        raise ReplayMismatchError(
            f"replaying reset seed {reset_seed}: the observation before step {t} differs from "
            f"the stored one ({replayed} vs {expected}); the env is not deterministic or the "
            "actions are not the episode's"
        )


def even_crop(frames: np.ndarray) -> np.ndarray:
    """Drop a last odd row and column of frames (L, H, W, 3): yuv420p needs even sizes."""
    h, w = frames.shape[1] - frames.shape[1] % 2, frames.shape[2] - frames.shape[2] % 2
    return frames[:, :h, :w]
