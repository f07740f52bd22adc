"""A clip recipe: everything that renders one behaviour's clip and poster, kept so that the
clip can be rendered when a person first asks for it (issue 22: render what is seen first).

A recipe holds the window (episode reset seed, first step, L, stride, fps), the frame
settings, the raw actions and stored observations from the step the replay begins at to the
window's end, and where the sampler captured them (`envs.physics_state`) the physics states
before the window's first frame and before its poster's. Rendering it gives, bit for bit,
the clip and poster `render_jobs.run_job` makes of the same window (tested):

- with a state: restore the state before step ``start − 1``, take that step again, render
  the window's frames (a poster alone: restore the state before the poster's step, one step,
  one frame) — a few milliseconds for a poster, ~0.2 s for a 47-frame Hopper clip, whatever
  the window's place in its episode;
- without (GridWorld, classic control, episodes sampled without snapshots): replay from the
  reset, as `replay.replay_windows` does for every clip of a pool;
- a recorded dataset's window (`envs.datasets.RecordedStates`: a state for every step): each
  frame drawn from its own state (``frame_states``), no step taken, so nothing is checked
  against a replay.

Every step taken is checked against the stored observation (`replay.check_observation`).

A recipe's key is the SHA-256 of its contents (and of the versions of MuJoCo and ffmpeg that
draw and encode it); the clip's id is ``key.mp4`` and the poster's ``key.jpg`` (or ``.png``)
in the clip store (`store.py`), which keeps the recipe itself under ``.recipes/key.npz``.
"""

import functools
import hashlib
import io
import json
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from groupwise.clips.env_cache import cached_env
from groupwise.clips.replay import (
    FrameSettings,
    check_observation,
    even_crop,
    replay_windows,
)
from groupwise.clips.timing import ClipTiming
from groupwise.clips.video import ClipEncoder, VideoConfig, poster_bytes, poster_frame
from groupwise.envs.datasets import RecordedStates
from groupwise.envs.physics_state import restore_physics_state, show_physics_state
from groupwise.episodes.fragments import Fragment, Trajectory
from groupwise.types import FloatArray

FORMAT = "groupwise.clip-recipe/1"

_NO_STATE = np.zeros(0, dtype=np.float64)


@dataclass(frozen=True)
class ClipRecipe:
    """One window's clip and poster, ready to render (module docstring)."""

    settings: FrameSettings
    reset_seed: int
    start: int  # the window's first step in its episode
    length: int  # L, steps of the window
    stride: int  # a frame every stride-th step
    fps: float
    origin: int  # the step the replay begins at: 0 (the reset) or start − 1 (`state`)
    state: FloatArray  # (S,) physics state before step `origin`; (0,) when replayed from reset
    poster_state: FloatArray  # (S,) physics state before step poster_step − 1, or (0,)
    actions: np.ndarray  # (start + L − 1 − origin, *action_shape) raw actions of steps origin …
    observations: FloatArray  # (start + L − origin, obs_dim) stored observations of origin …
    frame_states: FloatArray = field(default_factory=lambda: _NO_STATE)
    """(frames, S) the physics state each frame shows, for a recorded dataset's window
    (module docstring); (0,) otherwise."""

    def __post_init__(self) -> None:
        end = self.start + self.length
        if self.length < 1 or self.stride < 1 or not 0 <= self.origin <= self.start:
            raise ValueError(f"not a window: start {self.start}, origin {self.origin}")
        if self.origin > 0 and self.state.size == 0:
            raise ValueError("a recipe that does not begin at the reset needs a state")
        steps = end - self.origin
        if len(self.actions) != steps - 1 or len(self.observations) != steps:
            raise ValueError(
                f"{len(self.actions)} actions and {len(self.observations)} observations do "
                f"not cover steps {self.origin} … {end - 1}"
            )

    @property
    def frames(self) -> int:
        """Frames of the clip, ⌈L / stride⌉."""
        return -(-self.length // self.stride)

    @property
    def poster_step(self) -> int:
        """The episode step the poster shows (the clip's middle frame, `video.poster_frame`)."""
        return self.start + poster_frame(self.frames) * self.stride

    @property
    def key(self) -> str:
        """SHA-256 (hex) of everything the clip and poster depend on (module docstring)."""
        return _digest(self)

    def clip_id(self) -> str:
        return f"{self.key}.mp4"

    def poster_id(self) -> str:
        return f"{self.key}.{self.settings.video.poster_format}"

    def to_bytes(self) -> bytes:
        """The recipe as an ``.npz`` file (`from_bytes` reads it back)."""
        buffer = io.BytesIO()
        np.savez(
            buffer,
            header=np.array(json.dumps(_header(self))),
            state=self.state,
            poster_state=self.poster_state,
            actions=self.actions,
            observations=self.observations,
            frame_states=self.frame_states,
        )
        return buffer.getvalue()

    @classmethod
    def from_bytes(cls, data: bytes) -> "ClipRecipe":
        """A recipe written by `to_bytes`.

        Raises:
            ValueError: not a recipe of this format.
        """
        with np.load(io.BytesIO(data), allow_pickle=False) as arrays:
            header = json.loads(str(arrays["header"]))
            if header.get("format") != FORMAT:
                raise ValueError(f"not a clip recipe of format {FORMAT}: {header.get('format')}")
            frame = header["settings"]
            return cls(
                settings=FrameSettings(
                    frame["env"], frame["width"], frame["height"], VideoConfig(**frame["video"])
                ),
                reset_seed=int(header["reset_seed"]),
                start=int(header["start"]),
                length=int(header["length"]),
                stride=int(header["stride"]),
                fps=float(header["fps"]),
                origin=int(header["origin"]),
                state=arrays["state"],
                poster_state=arrays["poster_state"],
                actions=arrays["actions"],
                observations=arrays["observations"],
                frame_states=arrays["frame_states"] if "frame_states" in arrays else _NO_STATE,
            )

    @classmethod
    def read(cls, path: Path) -> "ClipRecipe":
        return cls.from_bytes(path.read_bytes())


def window_recipe(
    trajectory: Trajectory, fragment: Fragment, settings: FrameSettings, timing: ClipTiming
) -> ClipRecipe:
    """The recipe of `fragment`'s clip, a window of `trajectory` (its episode), rendered with
    `settings` at `timing`'s stride and rate; from the episode's snapshots when it has them
    (a recorded dataset's episode, whose snapshots are `RecordedStates`: each frame from
    its own state).

    Raises:
        ValueError: the fragment is not a window of this trajectory.
    """
    start, length = fragment.start, fragment.length
    end = start + length
    if fragment.episode != trajectory.episode or fragment.reset_seed != trajectory.reset_seed:
        raise ValueError(f"fragment {fragment.key} is not a window of episode {trajectory.episode}")
    if end > len(trajectory) or length != timing.steps:
        raise ValueError(f"fragment {fragment.key} does not fit its episode or the clip timing")
    if isinstance(trajectory.snapshots, RecordedStates):
        return _recorded_recipe(trajectory, trajectory.snapshots, start, settings, timing)
    state = trajectory.snapshots.get(start - 1) if start > 0 else None
    origin = start - 1 if state is not None else 0
    poster_step = start + poster_frame(timing.frames) * timing.stride
    poster_state = trajectory.snapshots.get(poster_step - 1) if poster_step > 0 else None
    # observations are stored up to step T − 1 only: the last window ends at most there
    return ClipRecipe(
        settings=settings,
        reset_seed=trajectory.reset_seed,
        start=start,
        length=length,
        stride=timing.stride,
        fps=timing.fps,
        origin=origin,
        state=_NO_STATE if state is None else np.asarray(state, dtype=np.float64),
        poster_state=_NO_STATE if poster_state is None else np.asarray(poster_state, np.float64),
        actions=np.asarray(trajectory.actions[origin : end - 1]),
        observations=np.asarray(trajectory.obs[origin:end]),
    )


def _recorded_recipe(
    trajectory: Trajectory,
    states: RecordedStates,
    start: int,
    settings: FrameSettings,
    timing: ClipTiming,
) -> ClipRecipe:
    """A recorded window's recipe: the state of each of its frames (module docstring)."""
    end = start + timing.steps
    frames = np.stack([states[start + j * timing.stride] for j in range(timing.frames)])
    return ClipRecipe(
        settings=settings,
        reset_seed=trajectory.reset_seed,
        start=start,
        length=timing.steps,
        stride=timing.stride,
        fps=timing.fps,
        origin=start,
        state=frames[0],
        poster_state=_NO_STATE,
        actions=np.asarray(trajectory.actions[start : end - 1]),
        observations=np.asarray(trajectory.obs[start:end]),
        frame_states=frames,
    )


@dataclass(frozen=True)
class RenderedMedia:
    """The encoded files of one recipe."""

    clip: bytes | None  # the MP4 (None: only the poster was asked for)
    poster: bytes  # the poster image


def render_recipe(
    recipe: ClipRecipe, env: gym.Env[Any, Any] | None = None, *, clip: bool = True
) -> RenderedMedia:
    """Render `recipe` in this process: its clip and poster, or (``clip=False``) its poster
    alone. Without `env`, uses this process's cached rendering env for the recipe's settings
    (`env_cache`).

    Raises:
        ReplayMismatchError: an observation differs from the stored one.
        RenderingUnavailableError: no offscreen GL backend.
        VideoEncodingError: ffmpeg failed.
    """
    env = env if env is not None else cached_env(recipe.settings)
    video = recipe.settings.video
    if not clip:
        return RenderedMedia(None, poster_bytes(_poster_frame(recipe, env), video))
    frames = even_crop(window_frames(recipe, env))
    poster = poster_bytes(frames[poster_frame(recipe.frames)], video)
    return RenderedMedia(_encode(recipe, frames) if clip else None, poster)


def window_frames(recipe: ClipRecipe, env: gym.Env[Any, Any]) -> np.ndarray:
    """The window's frames (⌈L / stride⌉, H, W, 3) uint8, uncropped, as `replay_windows`
    renders them: from the recipe's state when it has one, else replayed from the reset."""
    start, length, stride = recipe.start, recipe.length, recipe.stride
    if recipe.frame_states.size:
        return np.stack([_state_frame(env, recipe, state) for state in recipe.frame_states])
    if recipe.origin == 0:
        windows = replay_windows(
            env, recipe.reset_seed, recipe.actions, [start], length, recipe.observations,
            stride=stride,
        )  # fmt: skip
        ((_, replayed),) = list(windows)  # run to the window's end: every step is checked
        return replayed
    wanted = {start + j * stride: j for j in range(recipe.frames)}
    frames: np.ndarray | None = None
    for t in _restored_steps(recipe, env, recipe.state, recipe.origin, start + length - 1):
        j = wanted.get(t)
        if j is not None:
            frame = np.asarray(env.render())
            if frames is None:
                frames = np.empty((recipe.frames, *frame.shape), dtype=np.uint8)
            frames[j] = frame
    assert frames is not None
    return frames


def _poster_frame(recipe: ClipRecipe, env: gym.Env[Any, Any]) -> np.ndarray:
    """The poster's frame (H', W', 3), cropped even: one step from the state before the
    poster's step − 1, else from the recipe's state, else replayed from the reset."""
    step = recipe.poster_step
    if recipe.frame_states.size:
        state = recipe.frame_states[poster_frame(recipe.frames)]
        return even_crop(_state_frame(env, recipe, state)[None])[0]
    if recipe.poster_state.size or recipe.origin > 0:
        state, before = (recipe.state, recipe.origin)
        if recipe.poster_state.size:
            state, before = (recipe.poster_state, step - 1)
        for _ in _restored_steps(recipe, env, state, before, step):
            pass
        return even_crop(np.asarray(env.render())[None])[0]
    return replayed_posters(env, [recipe])[step]


def replayed_posters(
    env: gym.Env[Any, Any], recipes: Sequence[ClipRecipe]
) -> dict[int, np.ndarray]:
    """Poster frames (H', W', 3), cropped even, of windows of one episode replayed from its
    reset (recipes with ``origin == 0``, one reset seed), in one replay: step → frame."""
    longest = max(recipes, key=lambda r: r.start + r.length)
    if {r.reset_seed for r in recipes} != {longest.reset_seed} or longest.origin != 0:
        raise ValueError("posters replayed together must be windows of one episode from its reset")
    steps = sorted({r.poster_step for r in recipes})
    windows = replay_windows(
        env, longest.reset_seed, longest.actions, steps, 1, longest.observations
    )
    return {step: even_crop(frames)[0] for step, frames in windows}


def _state_frame(env: gym.Env[Any, Any], recipe: ClipRecipe, state: FloatArray) -> np.ndarray:
    """The frame (H, W, 3) uint8 of `state` shown without a step."""
    env.reset(seed=recipe.reset_seed)  # the wrappers' own bookkeeping, as a replay's
    show_physics_state(env, state)
    return np.asarray(env.render())


def _restored_steps(
    recipe: ClipRecipe, env: gym.Env[Any, Any], state: FloatArray, before: int, last: int
) -> Any:
    """Reset the env, restore `state` (before step `before`) and step on to `last`,
    checking every observation; yields each step t (the env then shows step t's state)."""
    env.reset(seed=recipe.reset_seed)  # the wrappers' own bookkeeping (time limit, order)
    restore_physics_state(env, state)
    for t in range(before, last):
        obs = env.step(recipe.actions[t - recipe.origin])[0]
        check_observation(obs, recipe.observations[t + 1 - recipe.origin], t + 1, recipe.reset_seed)
        yield t + 1


def _encode(recipe: ClipRecipe, frames: np.ndarray) -> bytes:
    """The MP4 of (cropped) frames, encoded as `render_jobs.run_job` encodes a clip."""
    _, height, width, _ = frames.shape
    with tempfile.TemporaryDirectory(prefix="groupwise-clip-") as tmp:
        path = Path(tmp) / "clip.mp4"
        video, fps = recipe.settings.video, recipe.fps
        with ClipEncoder([path], recipe.frames, width, height, video, fps) as encoder:
            for frame in frames:
                encoder.write(frame)
        return path.read_bytes()


def _header(recipe: ClipRecipe) -> dict[str, Any]:
    settings = recipe.settings
    return {
        "format": FORMAT,
        "settings": {
            "env": settings.env,
            "width": settings.width,
            "height": settings.height,
            "video": {
                "preset": settings.video.preset,
                "crf": settings.video.crf,
                "poster_format": settings.video.poster_format,
                "poster_quality": settings.video.poster_quality,
            },
        },
        "reset_seed": recipe.reset_seed,
        "start": recipe.start,
        "length": recipe.length,
        "stride": recipe.stride,
        "fps": recipe.fps,
        "origin": recipe.origin,
    }


def _digest(recipe: ClipRecipe) -> str:
    digest = hashlib.sha256()
    digest.update(json.dumps({**_header(recipe), "renderer": _versions()}, sort_keys=True).encode())
    names = ("state", "poster_state", "actions", "observations")
    for name in (*names, "frame_states") if recipe.frame_states.size else names:
        array = np.ascontiguousarray(getattr(recipe, name))
        digest.update(f"{name} {array.dtype.str} {array.shape}".encode())
        digest.update(array.tobytes())
    return digest.hexdigest()


@functools.cache
def _versions() -> dict[str, str]:
    """The versions of what draws and encodes frames: a recipe's key changes with them."""
    found = {}
    for package in ("mujoco", "gymnasium", "imageio-ffmpeg", "pillow"):
        try:
            found[package] = metadata.version(package)
        except metadata.PackageNotFoundError:
            found[package] = ""
    return found
