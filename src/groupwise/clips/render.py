"""Rendering and encoding the clips of a pool in worker processes.

Work is planned per episode (`plan_jobs`): one replay (`replay.replay_windows`) renders all
the selected windows of an episode, or of a contiguous chunk of them so that a small pool
still keeps every worker busy. A worker streams each rendered window into one ffmpeg process
per job (`video.ClipEncoder`, which encodes while the next window renders), stores the MP4s
and posters in the clip store (`store.py`) and returns their ids. Workers are started with
"spawn": numba's threading layer, used for the DTW distances in the parent, kills forked
children (so a script that prepares pools needs the ``if __name__ == "__main__"`` guard).
Each worker makes its rendering env once and reuses it, so results do not depend on which
worker ran which job (tested: clips rendered in-process and by workers have equal ids).
Workers say over a queue each time a clip's frames are rendered and handed to ffmpeg, so
`PendingClips.wait` reports clips as they are done, not only jobs (a job is about 1/8 of a
pool: several seconds).
"""

import itertools
import logging
import math
import multiprocessing
import queue
import resource
import time
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, Executor, Future, ProcessPoolExecutor
from concurrent.futures import wait as wait_futures
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from tqdm.auto import tqdm

from groupwise.clips.replay import FrameSettings, even_crop, make_render_env, replay_windows
from groupwise.clips.store import ClipStore
from groupwise.clips.video import DEFAULT_FPS, ClipEncoder, poster_bytes, poster_frame
from groupwise.pool.fragments import Fragment, Trajectory
from groupwise.types import ProgressFn

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
    env = env if env is not None else _cached_env(job.settings)
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


def _children_cpu_s() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


_ENVS: dict[FrameSettings, gym.Env[Any, Any]] = {}
"""This process's rendering envs, one per settings (a worker renders many jobs)."""


def _cached_env(settings: FrameSettings) -> gym.Env[Any, Any]:
    env = _ENVS.get(settings)
    if env is None:
        env = _ENVS[settings] = make_render_env(settings)
    return env


def _warm_up(settings: FrameSettings) -> float:
    """Make (and cache) this worker's env and render one frame; returns the seconds it took."""
    start = time.perf_counter()
    env = _cached_env(settings)
    env.reset(seed=0)
    env.render()
    return time.perf_counter() - start


_CLIPS_DONE: "multiprocessing.Queue[int] | None" = None
"""This worker's queue to its parent: the batch number of each clip it rendered."""


def _start_worker(clips_done: "multiprocessing.Queue[int]") -> None:
    global _CLIPS_DONE
    _CLIPS_DONE = clips_done
    # progress only: a worker that exits must not wait for its parent to read the queue
    clips_done.cancel_join_thread()


def _run_job_in_worker(job: ClipJob, root: Path, batch: int) -> JobReport:
    done = _CLIPS_DONE
    return run_job(job, ClipStore(root), on_clip=None if done is None else lambda: done.put(batch))


class RenderPool:
    """Worker processes ("spawn") that render and encode clips; reusable across pools.

    `workers=0` renders in the calling process (for debugging and tiny pools). Use as a
    context manager, or call `close`.
    """

    def __init__(self, workers: int = 2) -> None:
        if workers < 0:
            raise ValueError(f"workers must be >= 0, got {workers}")
        self.workers = workers
        self._executor: Executor | None = None
        self._warming: list[Future[float]] = []
        self._batches = itertools.count()
        self._clips_done: multiprocessing.Queue[int] | None = None
        if workers > 0:
            context = multiprocessing.get_context("spawn")
            self._clips_done = context.Queue()
            self._executor = ProcessPoolExecutor(
                max_workers=workers,
                mp_context=context,
                initializer=_start_worker,
                initargs=(self._clips_done,),
            )

    def __enter__(self) -> "RenderPool":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        if self._executor is not None:
            self._executor.shutdown(wait=True, cancel_futures=True)
            self._executor = None
        if self._clips_done is not None:
            self._clips_done.close()
            self._clips_done = None

    def warm_up(self, settings: FrameSettings) -> None:
        """Start the workers and make their envs now, without waiting (e.g. while the
        parent samples episodes). Errors surface in `PendingClips.wait`."""
        if self._executor is not None:
            self._warming = [self._executor.submit(_warm_up, settings) for _ in range(self.workers)]

    def start(self, jobs: Sequence[ClipJob], store: ClipStore) -> "PendingClips":
        """Hand every job to the workers and return at once; `wait` collects the reports.
        (With `workers=0` the jobs run in `wait`.)"""
        warming, self._warming = self._warming, []
        if self._executor is None:
            return PendingClips(list(jobs), store, warming, {})
        batch = next(self._batches)
        futures = {
            self._executor.submit(_run_job_in_worker, job, store.root, batch): i
            for i, job in enumerate(jobs)
        }
        return PendingClips(list(jobs), store, warming, futures, self._clips_done, batch)

    def render(
        self,
        jobs: Sequence[ClipJob],
        store: ClipStore,
        show_progress: bool = True,
        progress: ProgressFn | None = None,
    ) -> list[JobReport]:
        """`start` then `wait`."""
        return self.start(jobs, store).wait(show_progress, progress)


class PendingClips:
    """Jobs handed to a `RenderPool`; `wait` returns their reports in job order."""

    def __init__(
        self,
        jobs: list[ClipJob],
        store: ClipStore,
        warming: list[Future[float]],
        futures: Mapping[Future[JobReport], int],
        clips_done: "multiprocessing.Queue[int] | None" = None,
        batch: int = 0,
    ) -> None:
        self._jobs = jobs
        self._store = store
        self._warming = warming
        self._futures = futures
        self._clips_done = clips_done
        self._batch = batch

    def wait(
        self, show_progress: bool = True, progress: ProgressFn | None = None
    ) -> list[JobReport]:
        """Block until every job is done; a tqdm bar counts clips, and `progress` hears
        (clips done, clips) as the workers finish each clip (at most every `POLL_S`).

        Raises the first failed job's error (e.g. `ReplayMismatchError`,
        `RenderingUnavailableError`, `VideoEncodingError`); the other jobs are cancelled.
        """
        jobs = self._jobs
        total = sum(len(job.starts) for job in jobs)
        reports: dict[int, JobReport] = {}
        with tqdm(total=total, unit="clip", desc="clips", disable=not show_progress) as bar:
            counter = _ClipCounter(total, bar, progress)
            try:
                for warming in self._warming:
                    warming.result()
                if not self._futures:
                    reports = self._run_here(counter)
                pending = set(self._futures)
                while pending:
                    finished, pending = wait_futures(
                        pending, timeout=POLL_S, return_when=FIRST_COMPLETED
                    )
                    for future in finished:
                        reports[self._futures[future]] = future.result()
                    counter.add(self._drain())
                counter.finish()
            except BaseException:
                for future in self._futures:
                    future.cancel()
                raise
        return [reports[i] for i in range(len(jobs))]

    def _drain(self) -> int:
        """Clips of this batch the workers reported since the last call (earlier batches'
        late reports, of a batch that failed, are dropped)."""
        count = 0
        while self._clips_done is not None:
            try:
                count += self._clips_done.get_nowait() == self._batch
            except queue.Empty:
                break
        return count

    def _run_here(self, counter: "_ClipCounter") -> dict[int, JobReport]:
        envs: dict[FrameSettings, gym.Env[Any, Any]] = {}
        reports = {}
        try:
            for i, job in enumerate(self._jobs):
                if job.settings not in envs:
                    envs[job.settings] = make_render_env(job.settings)
                reports[i] = run_job(
                    job, self._store, envs[job.settings], on_clip=lambda: counter.add(1)
                )
        finally:
            for env in envs.values():
                env.close()
        return reports


POLL_S = 0.25
"""How often `PendingClips.wait` collects the workers' clip reports."""


class _ClipCounter:
    """Clips done so far, shown on a tqdm bar and told to a `ProgressFn` as they grow."""

    def __init__(self, total: int, bar: Any, progress: ProgressFn | None) -> None:
        self.total, self.bar, self.progress, self.done = total, bar, progress, 0
        if progress is not None:
            progress(0, total)

    def add(self, clips: int) -> None:
        if clips:
            self._set(min(self.done + clips, self.total))

    def finish(self) -> None:
        self._set(self.total)

    def _set(self, done: int) -> None:
        if done > self.done:
            self.bar.update(done - self.done)
            self.done = done
            if self.progress is not None:
                self.progress(done, self.total)
