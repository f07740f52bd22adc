"""A clip job: one episode's selected windows, replayed, rendered and encoded (`run_job`),
and how a pool's windows are cut into jobs (`plan_jobs`); a poster job: windows whose clips
are rendered on demand, their recipes kept in the store and only their posters rendered now
(`run_poster_job`, `plan_poster_jobs`). `render.RenderPool` runs both in worker processes;
they also run in this process (`workers=0`).
"""

import logging
import math
import resource
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np

from groupwise.clips.env_cache import cached_env
from groupwise.clips.recipe import ClipRecipe, render_recipe, replayed_posters, window_recipe
from groupwise.clips.replay import FrameSettings, even_crop, replay_windows
from groupwise.clips.store import ClipStore
from groupwise.clips.timing import ClipTiming
from groupwise.clips.video import DEFAULT_FPS, ClipEncoder, poster_bytes, poster_frame
from groupwise.episodes.fragments import Fragment, Trajectory

logger = logging.getLogger(__name__)

JOBS_PER_WORKER = 4
"""Episodes with many selected windows are split into chunks so that there are at least this
many jobs per worker (a chunk replays from the reset, which costs only physics steps)."""


@dataclass(frozen=True)
class ClipJob:
    """Render the windows `starts` (ascending) of one episode, `length` steps each, a frame
    every `stride`-th step, into clips playing at `fps` frames per second."""

    settings: FrameSettings
    episode: int
    reset_seed: int
    actions: np.ndarray  # (T, *action_shape) raw actions of steps 0 … T - 1, T = last end - 1
    observations: np.ndarray  # (T + 1, obs_dim) stored observations of steps 0 … T, for the check
    starts: tuple[int, ...]
    length: int
    stride: int = 1
    fps: float = DEFAULT_FPS

    @property
    def clip_frames(self) -> int:
        """Frames of each clip, ⌈length / stride⌉."""
        return -(-self.length // self.stride)

    @property
    def frames(self) -> int:
        return len(self.starts) * self.clip_frames

    @property
    def cost(self) -> float:
        """Rough relative cost (a physics step costs ~1/50 of a rendered frame)."""
        return self.frames + len(self.actions) / 50


@dataclass(frozen=True)
class RenderedClip:
    """The stored clip and poster of one window."""

    episode: int
    start: int
    clip: str  # clip-store id of the MP4
    poster: str  # clip-store id of the poster image


@dataclass(frozen=True)
class JobReport:
    """What one job produced and where its worker's time went (seconds)."""

    clips: tuple[RenderedClip, ...]
    replay_s: float  # stepping and checking observations
    render_s: float  # env.render()
    encode_s: float  # handing frames to ffmpeg, waiting for it, posters, storing files
    ffmpeg_cpu_s: float  # CPU time of the job's ffmpeg process (it runs beside the worker)


def plan_jobs(
    trajectories: Sequence[Trajectory],
    fragments: Sequence[Fragment],
    settings: FrameSettings,
    workers: int,
    *,
    stride: int = 1,
    fps: float = DEFAULT_FPS,
) -> list[ClipJob]:
    """One job per episode with selected windows, episodes with many windows split into
    contiguous chunks (`JOBS_PER_WORKER`); most expensive first, for load balance. Clips
    get a frame every `stride`-th step and play at `fps` (`clips.timing`).

    Every fragment must come from one of `trajectories` (matched by episode and reset seed)
    and all fragments must have one length.

    Raises:
        ValueError: a fragment's episode is missing, or lengths differ.
    """
    if not fragments:
        return []
    lengths = {f.length for f in fragments}
    if len(lengths) != 1:
        raise ValueError(f"fragments disagree on length: {sorted(lengths)}")
    length = lengths.pop()
    by_episode = {t.episode: t for t in trajectories}
    starts: dict[int, list[int]] = {}
    for fragment in fragments:
        traj = by_episode.get(fragment.episode)
        if traj is None or traj.reset_seed != fragment.reset_seed:
            raise ValueError(f"fragment {fragment.key} has no trajectory to replay")
        if fragment.start + length > len(traj):
            raise ValueError(f"fragment {fragment.key} runs past its episode's end")
        starts.setdefault(fragment.episode, []).append(fragment.start)
    per_job = max(1, math.ceil(len(fragments) / (JOBS_PER_WORKER * max(workers, 1))))
    jobs = []
    for episode, episode_starts in starts.items():
        traj = by_episode[episode]
        ordered = sorted(set(episode_starts))
        for i in range(0, len(ordered), per_job):
            chunk = tuple(ordered[i : i + per_job])
            last = chunk[-1] + length - 1  # index of the last frame's step
            jobs.append(
                ClipJob(
                    settings=settings,
                    episode=episode,
                    reset_seed=traj.reset_seed,
                    actions=np.asarray(traj.actions[:last]),
                    observations=np.asarray(traj.obs[: last + 1]),
                    starts=chunk,
                    length=length,
                    stride=stride,
                    fps=fps,
                )
            )
    return sorted(jobs, key=lambda job: -job.cost)


def run_job(
    job: ClipJob,
    store: ClipStore,
    env: gym.Env[Any, Any] | None = None,
    on_clip: Callable[[], None] | None = None,
) -> JobReport:
    """Render, encode and store every window of one job (in whichever process calls it).

    All the job's clips go through one ffmpeg process (`ClipEncoder`), which encodes a window
    while the next is rendered. Without `env`, uses this process's cached rendering env.
    `on_clip` is called as each window's frames and poster are done.
    """
    env = env if env is not None else cached_env(job.settings)
    timings: dict[str, float] = {}
    encode_s = 0.0
    cpu_before = _children_cpu_s()
    tmp = [store.temporary_file("mp4") for _ in job.starts]
    encoder: ClipEncoder | None = None
    posters = []
    try:
        windows = replay_windows(
            env,
            job.reset_seed,
            job.actions,
            job.starts,
            job.length,
            job.observations,
            timings,
            job.stride,
        )
        for _, frames in windows:
            tick = time.perf_counter()
            frames = even_crop(frames)
            if encoder is None:
                _, height, width, _ = frames.shape
                encoder = ClipEncoder(
                    tmp, job.clip_frames, width, height, job.settings.video, job.fps
                )
            for frame in frames:
                encoder.write(frame)
            image = poster_bytes(frames[poster_frame(job.clip_frames)], job.settings.video)
            posters.append(store.put_bytes(image, job.settings.video.poster_format))
            encode_s += time.perf_counter() - tick
            if on_clip is not None:
                on_clip()
        tick = time.perf_counter()
        if encoder is not None:
            encoder.close()
        clips = [store.put_file(path, "mp4") for path in tmp]
        encode_s += time.perf_counter() - tick
    except BaseException:
        if encoder is not None:
            encoder.close(failed=True)
        raise
    finally:
        for path in tmp:
            path.unlink(missing_ok=True)
    rendered = tuple(
        RenderedClip(job.episode, start, clip, poster)
        for start, clip, poster in zip(job.starts, clips, posters, strict=True)
    )
    return JobReport(
        clips=rendered,
        replay_s=timings["replay_s"],
        render_s=timings["render_s"],
        encode_s=encode_s,
        ffmpeg_cpu_s=_children_cpu_s() - cpu_before,
    )


@dataclass(frozen=True)
class PosterJob:
    """Windows whose clips are rendered on demand: keep each one's recipe in the store and
    render its poster now (`run_poster_job`)."""

    windows: tuple[tuple[int, ClipRecipe], ...]  # (episode, recipe) of each window

    @property
    def clips(self) -> int:
        return len(self.windows)


def plan_poster_jobs(
    trajectories: Sequence[Trajectory],
    fragments: Sequence[Fragment],
    settings: FrameSettings,
    timing: ClipTiming,
    workers: int,
) -> list[PosterJob]:
    """The recipes of `fragments` (`recipe.window_recipe`), in about `JOBS_PER_WORKER` jobs
    per worker.

    Raises:
        ValueError: a fragment's episode is missing, or it does not fit the timing.
    """
    by_episode = {t.episode: t for t in trajectories}
    windows = []
    for fragment in fragments:
        traj = by_episode.get(fragment.episode)
        if traj is None:
            raise ValueError(f"fragment {fragment.key} has no trajectory to replay")
        windows.append((fragment.episode, window_recipe(traj, fragment, settings, timing)))
    per_job = max(1, math.ceil(len(windows) / (JOBS_PER_WORKER * max(workers, 1))))
    return [PosterJob(tuple(windows[i : i + per_job])) for i in range(0, len(windows), per_job)]


def run_poster_job(
    job: PosterJob, store: ClipStore, on_clip: Callable[[], None] | None = None
) -> JobReport:
    """Keep every window's recipe in `store` and render its poster (unless stored); the
    reported clip and poster ids are the recipe's (``key.mp4``, ``key.jpg``). Windows with
    a poster snapshot take one step each; the others are replayed, one replay per episode
    (`recipe.replayed_posters`)."""
    rendered = []
    render_s = encode_s = 0.0
    cpu_before = _children_cpu_s()
    tick = time.perf_counter()
    replayed = _replayed_posters([r for _, r in job.windows if r.poster_id() not in store])
    render_s += time.perf_counter() - tick
    for episode, recipe in job.windows:
        tick = time.perf_counter()
        key = recipe.key
        store.put_recipe(key, recipe.to_bytes())
        poster = recipe.poster_id()
        mark = time.perf_counter()
        encode_s += mark - tick
        if poster not in store:
            frame = replayed.get((recipe.settings, recipe.reset_seed, recipe.poster_step))
            if frame is None:
                image = render_recipe(recipe, clip=False).poster
            else:
                image = poster_bytes(frame, recipe.settings.video)
            tick = time.perf_counter()
            render_s += tick - mark
            store.put_as(image, poster)
            encode_s += time.perf_counter() - tick
        rendered.append(RenderedClip(episode, recipe.start, recipe.clip_id(), poster))
        if on_clip is not None:
            on_clip()
    return JobReport(
        clips=tuple(rendered),
        replay_s=0.0,
        render_s=render_s,
        encode_s=encode_s,
        ffmpeg_cpu_s=_children_cpu_s() - cpu_before,
    )


def _replayed_posters(
    recipes: Sequence[ClipRecipe],
) -> dict[tuple[FrameSettings, int, int], np.ndarray]:
    """Poster frames of the recipes without snapshots (origin 0, no poster state), one
    replay per episode: (settings, reset seed, step) → frame."""
    episodes: dict[tuple[FrameSettings, int], list[ClipRecipe]] = {}
    for recipe in recipes:
        if recipe.origin == 0 and recipe.poster_state.size == recipe.frame_states.size == 0:
            episodes.setdefault((recipe.settings, recipe.reset_seed), []).append(recipe)
    frames = {}
    for (settings, seed), group in episodes.items():
        for step, frame in replayed_posters(cached_env(settings), group).items():
            frames[(settings, seed, step)] = frame
    return frames


def _children_cpu_s() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime
