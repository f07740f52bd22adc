"""Rendering and encoding the clips of a pool in worker processes (or, for a pool whose clips
are rendered on demand, its posters and clip recipes: `render_jobs.PosterJob`).

Work is planned per episode (`render_jobs.plan_jobs`): one replay (`replay.replay_windows`)
renders all the selected windows of an episode, or of a contiguous chunk of them so that a
small pool still keeps every worker busy. A worker streams each rendered window into one
ffmpeg process per job (`video.ClipEncoder`, which encodes while the next window renders),
stores the MP4s and posters in the clip store (`store.py`) and returns their ids. Workers
are started with "spawn": numba's threading layer, used for the DTW distances in the parent,
kills forked children (so a script that prepares pools needs the ``if __name__ ==
"__main__"`` guard). Each worker makes its rendering env once and reuses it, so results do
not depend on which worker ran which job (tested: clips rendered in-process and by workers
have equal ids). Workers say over a queue each time a clip's frames are rendered and handed
to ffmpeg, so `PendingClips.wait` reports clips as they are done, not only jobs (a job is
about 1/8 of a pool: several seconds).
"""

import itertools
import logging
import multiprocessing
import queue
from collections.abc import Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, Executor, Future, ProcessPoolExecutor
from concurrent.futures import wait as wait_futures
from pathlib import Path
from typing import Any

import gymnasium as gym
from tqdm.auto import tqdm

from groupwise.clips.env_cache import warm_up
from groupwise.clips.render_jobs import (
    ClipJob,
    JobReport,
    PosterJob,
    run_job,
    run_poster_job,
)
from groupwise.clips.replay import FrameSettings, make_render_env
from groupwise.clips.store import ClipStore
from groupwise.types import ProgressFn

logger = logging.getLogger(__name__)

_CLIPS_DONE: "multiprocessing.Queue[int] | None" = None
"""This worker's queue to its parent: the batch number of each clip it rendered."""


def _start_worker(clips_done: "multiprocessing.Queue[int]") -> None:
    global _CLIPS_DONE
    _CLIPS_DONE = clips_done
    # progress only: a worker that exits must not wait for its parent to read the queue
    clips_done.cancel_join_thread()


Job = ClipJob | PosterJob
"""What a `RenderPool` runs: a pool's clips rendered now, or their posters only."""


def _run_job_in_worker(job: Job, root: Path, batch: int) -> JobReport:
    done = _CLIPS_DONE
    on_clip = None if done is None else lambda: done.put(batch)
    if isinstance(job, PosterJob):
        return run_poster_job(job, ClipStore(root), on_clip)
    return run_job(job, ClipStore(root), on_clip=on_clip)


def _clips(job: Job) -> int:
    return job.clips if isinstance(job, PosterJob) else len(job.starts)


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
            self._warming = [self._executor.submit(warm_up, settings) for _ in range(self.workers)]

    def start(self, jobs: Sequence[Job], store: ClipStore) -> "PendingClips":
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
        jobs: Sequence[Job],
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
        jobs: list[Job],
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
        total = sum(_clips(job) for job in jobs)
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
                if isinstance(job, PosterJob):
                    reports[i] = run_poster_job(job, self._store, lambda: counter.add(1))
                    continue
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
