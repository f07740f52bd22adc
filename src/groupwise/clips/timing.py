"""How long a behaviour lasts and how its clip plays: simulated time, real speed (SPEC §9).

A behaviour covers a stretch of simulated time: L = round(seconds / dt) env steps, dt being
the env's seconds per step (`step_seconds`). Its clip plays at real speed: a frame every k-th
step, k = max(1, round(1 / (TARGET_FPS · dt))), so the clip's frame rate 1 / (k · dt) stays
near `TARGET_FPS` and one second of clip is one second of simulation. The clip has ⌈L / k⌉
frames; frame j shows the state before step start + j·k. Only rendering strides: the reward
model, the DTW features and the preference pairs use every step of the window.

Envs: the MuJoCo envs have a physical dt (``env.unwrapped.dt``: Hopper and Walker2d 0.008 s,
HalfCheetah 0.05 s, Reacher 0.02 s); envs without one (classic control, GridWorld) declare
how fast they are meant to be watched (``metadata["render_fps"]``, dt = 1 / render_fps);
an env with neither is taken to run at `TARGET_FPS` steps per second.
"""

import functools
import math
from dataclasses import dataclass
from typing import Any

import gymnasium as gym

from groupwise.clips.video import poster_frame
from groupwise.envs import env_entry, make_env

TARGET_FPS = 30.0
"""Frame rate a clip's stride aims at (browsers and people are at ease with 25-60)."""

DEFAULT_CLIP_SECONDS = 1.0
"""Simulated seconds of a behaviour of an env that names no duration of its own
(`groupwise.envs.EnvEntry.clip_seconds`)."""


@dataclass(frozen=True)
class ClipTiming:
    """The time a behaviour covers and how its clip plays it."""

    step_seconds: float
    """dt, simulated seconds per env step."""
    steps: int
    """L, env steps per behaviour (the reward model's and the DTW's window)."""
    stride: int
    """k, a frame is rendered every k-th step."""

    def __post_init__(self) -> None:
        if not self.step_seconds > 0 or not math.isfinite(self.step_seconds):
            raise ValueError(f"step_seconds must be positive, got {self.step_seconds}")
        if self.steps < 1 or self.stride < 1:
            raise ValueError(f"steps and stride must be >= 1, got {self.steps}, {self.stride}")

    @property
    def frames(self) -> int:
        """Frames per clip, ⌈L / k⌉."""
        return -(-self.steps // self.stride)

    @property
    def poster_offset(self) -> int:
        """Steps into the window of the poster's frame (`clips.video.poster_frame`)."""
        return poster_frame(self.frames) * self.stride

    @property
    def snapshot_offsets(self) -> tuple[int, ...]:
        """Steps into a window whose physics state before them renders the window without
        its episode's replay (`rl.rollout.sample_episodes_for_windows`): the first frame's
        (the clip) and the poster's."""
        return (0, self.poster_offset) if self.poster_offset else (0,)

    @property
    def fps(self) -> float:
        """Playback frame rate, 1 / (k · dt): real speed."""
        return 1.0 / (self.stride * self.step_seconds)

    @property
    def seconds(self) -> float:
        """Simulated (and playback) duration of a behaviour, L · dt."""
        return self.steps * self.step_seconds

    @property
    def speed(self) -> float:
        """Playback speed relative to simulated time: 1.0, real speed, by construction."""
        return self.fps * self.stride * self.step_seconds

    def as_json(self) -> dict[str, float | int]:
        """The timing as ``pool.json`` and the API carry it."""
        return {
            "steps": self.steps,
            "stride": self.stride,
            "frames": self.frames,
            "fps": round(self.fps, 6),
            "seconds": round(self.seconds, 6),
            "speed": round(self.speed, 6),
            "step_seconds": self.step_seconds,
        }


def clip_timing(
    step_seconds: float,
    seconds: float | None = None,
    *,
    steps: int | None = None,
    target_fps: float = TARGET_FPS,
) -> ClipTiming:
    """The timing of a behaviour of `seconds` simulated seconds (L = round(seconds / dt),
    at least 1), or of exactly `steps` steps, in an env of `step_seconds` = dt per step.

    Raises:
        ValueError: not exactly one of `seconds` and `steps`, or a non-positive value.
    """
    if not step_seconds > 0 or not target_fps > 0:
        raise ValueError(f"step_seconds and target_fps must be positive, got {step_seconds}")
    if (seconds is None) == (steps is None):
        raise ValueError("give either seconds or steps")
    if seconds is not None:
        if not seconds > 0:
            raise ValueError(f"seconds must be positive, got {seconds}")
        steps = max(1, round(seconds / step_seconds))
    assert steps is not None
    stride = max(1, round(1.0 / (target_fps * step_seconds)))
    return ClipTiming(step_seconds, steps, stride)


def step_seconds(env: gym.Env[Any, Any]) -> float:
    """dt of an env: ``unwrapped.dt``, else 1 / ``metadata["render_fps"]``, else
    1 / `TARGET_FPS` (module docstring)."""
    base = env.unwrapped
    dt = getattr(base, "dt", None)
    if isinstance(dt, int | float) and math.isfinite(dt) and dt > 0:
        return float(dt)
    fps = base.metadata.get("render_fps")
    if isinstance(fps, int | float) and math.isfinite(fps) and fps > 0:
        return 1.0 / float(fps)
    return 1.0 / TARGET_FPS


@functools.cache
def env_step_seconds(env: str) -> float:
    """dt of an env by name (`groupwise.envs.make_env`'s names); made once per process.

    Raises:
        ValueError: unknown env.
    """
    instance = make_env(env)
    try:
        return step_seconds(instance)
    finally:
        instance.close()


GYMNASIUM_CLIP_SECONDS: dict[str, float] = {
    # Swimmer-v5 (dt 0.04 s): under random actions its joints turn ~0.2 rad and its head
    # moves 0.1 m in 1 s, nothing to judge; in 4 s 1-1.4 rad and 0.8 m, a few strokes (and a
    # good policy's ~0.1 m/s, 0.4 m of its 3 m body). Issue 23.
    "Swimmer": 4.0,
}
"""Default clip seconds of Gymnasium envs by family (the id without namespace and version:
"Swimmer" for ``Swimmer-v5`` and ``Swimmer-v4``) that move too slowly for 1 s clips."""


def default_clip_seconds(env: str) -> float:
    """The simulated seconds a behaviour of `env` covers by default: its `EnvEntry`'s, else
    its family's in `GYMNASIUM_CLIP_SECONDS`, else `DEFAULT_CLIP_SECONDS`."""
    entry = env_entry(env)
    seconds = entry.clip_seconds if entry is not None else None
    if seconds is None and entry is None:
        seconds = GYMNASIUM_CLIP_SECONDS.get(env.split(":")[-1].split("/")[-1].split("-v")[0])
    return float(seconds) if seconds is not None else DEFAULT_CLIP_SECONDS


def env_clip_timing(
    env: str, seconds: float | None = None, *, steps: int | None = None
) -> ClipTiming:
    """The clip timing of `env`: `steps` steps if given, else `seconds` simulated seconds
    (default: `default_clip_seconds`).

    Raises:
        ValueError: unknown env, or a non-positive duration.
    """
    dt = env_step_seconds(env)
    if steps is not None:
        return clip_timing(dt, steps=steps)
    return clip_timing(dt, seconds if seconds is not None else default_clip_seconds(env))
