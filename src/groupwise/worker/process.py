"""The training worker: a process of its own that polls the database for jobs.

It looks for sessions whose phase is ``preparing``, ``training`` or ``finishing`` (the
longest-waiting first), runs the job (`jobs.prepare` / `jobs.train` / `finishing.finish`)
with progress written to the session row, and goes back to polling. It never talks HTTP;
the server and it share only the database and the data directory. A job that raises marks
its session ``failed`` with the error, and the worker goes on serving the other sessions.

Started by the server's `Supervisor` with the "spawn" context (numba's threading layer kills
forked children) and with one thread per numeric library: OMP_NUM_THREADS is set to 1
before the process starts, torch to one thread inside it (numba's OpenMP layer otherwise
resets torch to every core, and the nets are tiny), and the DTW kernels to one thread
(`behaviour.set_kernel_threads`). NUMBA_NUM_THREADS is the cores, so that preparing a round,
while nothing else of the worker's runs, measures its distances on the cores other work
leaves free (`jobs.prepare`); the kernels are compiled (or loaded from numba's cache) at
the start, not in a user's first round.

The worker leads a process group of its own, which its render processes and their ffmpeg
encoders join: the supervisor ends the whole group when it stops the worker or finds it
dead, so no render process outlives it. The worker ends its group by itself when its
parent (the server) is gone, so a killed server leaves no orphan that a restarted one
would race.
"""

import logging
import multiprocessing
import os
import signal
import time
import zlib
from pathlib import Path
from typing import TYPE_CHECKING

from groupwise.storage import Database
from groupwise.storage.lifecycle import mark_failed
from groupwise.storage.sessions import worker_sessions
from groupwise.worker.progress import JobProgress, ProgressReporter

if TYPE_CHECKING:  # the server imports this module; only the worker process needs these
    from groupwise.clips.render import RenderPool
    from groupwise.worker.continuous import ContinuousSessions
    from groupwise.worker.job import Job

log = logging.getLogger(__name__)

THREAD_ENV = {
    "NUMBA_NUM_THREADS": str(
        len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    ),
    "OMP_NUM_THREADS": "1",
    "MKL_NUM_THREADS": "1",
}
"""Set in the environment the worker is spawned with (see the module docstring)."""


def shard_of(session_id: str, count: int) -> int:
    """Which of `count` worker processes serves a session: a stable hash of its id, the
    same in every process and after a restart."""
    return zlib.crc32(session_id.encode()) % count


def worker_main(
    database_url: str,
    data_dir: str,
    poll_s: float,
    log_level: int,
    shard: tuple[int, int] = (0, 1),
) -> None:
    """The worker process's entry point: poll for jobs until the parent process is gone.
    `shard` (index, count): this worker serves the sessions `shard_of` gives its index."""
    os.setpgrp()  # see the module docstring
    # SIGTERM (the supervisor stopping it) unwinds the job, so the render pool shuts down
    # cleanly; the step re-runs when a server starts again.
    signal.signal(signal.SIGTERM, _stop)
    import torch

    from groupwise.behaviour import set_kernel_threads, warm_up

    torch.set_num_threads(1)
    # torch checks every distribution's arguments (SB3 builds one per policy call): a
    # quarter of each call's time when a pool is sampled at End round (issue 39); the
    # checks change no number
    torch.distributions.Distribution.set_default_validate_args(False)
    logging.basicConfig(
        level=logging.WARNING, format="%(asctime)s %(levelname)s %(name)s: %(message)s"
    )
    logging.getLogger("groupwise").setLevel(log_level)
    set_kernel_threads(1)
    log.info("DTW kernels ready in %.1f s", warm_up())
    db = Database(database_url, pool_size=2)
    Worker(db, Path(data_dir), poll_s, shard).run()


def _stop(signum: int, frame: object) -> None:
    raise SystemExit(0)


def _parent_alive() -> bool:
    parent = multiprocessing.parent_process()
    return parent is None or parent.is_alive()


def _exit_if_orphaned() -> None:
    if not _parent_alive():
        log.warning("the server is gone; the training worker exits")
        os.killpg(os.getpgrp(), signal.SIGKILL)  # this process and its render processes


def kill_group(pid: int) -> None:
    """End the process group led by worker `pid` (its render processes), if any is left."""
    try:
        os.killpg(pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass


class Worker:
    """Runs jobs one at a time; the render pool is kept across rounds."""

    def __init__(
        self, db: Database, data_dir: Path, poll_s: float, shard: tuple[int, int] = (0, 1)
    ) -> None:
        self.db = db
        self.data_dir = data_dir
        self.poll_s = poll_s
        self.shard = shard
        self._render: dict[int, RenderPool] = {}
        self._continuous: ContinuousSessions | None = None

    @property
    def continuous(self) -> "ContinuousSessions":
        """The continuous rounds this worker trains (`worker.continuous`; loaded on first use, as
        the server imports this module)."""
        if self._continuous is None:
            from groupwise.worker.continuous import ContinuousSessions

            self._continuous = ContinuousSessions(
                self.db, self.data_dir, self.serves, self._render_pool
            )
        return self._continuous

    def serves(self, session_id: str) -> bool:
        """Whether this worker serves the session (its `shard`)."""
        index, count = self.shard
        return count == 1 or shard_of(session_id, count) == index

    def run(self) -> None:
        index, count = self.shard
        log.info(
            "training worker %d started%s",
            os.getpid(),
            f" (shard {index} of {count})" if count > 1 else "",
        )
        try:
            while _parent_alive():
                if not self.work_once():
                    time.sleep(self.poll_s)
        finally:
            self.close()
        _exit_if_orphaned()

    def close(self) -> None:
        """End the render and evaluation processes rather than wait for their work (one may
        still be starting), so that a stopping worker exits, and unlinks its semaphores,
        before the supervisor's kill would leak them (issue 40). It ends every child of
        this process: for the worker process, which has no others."""
        for child in multiprocessing.active_children():
            child.terminate()
        self._close_render_pools()
        if self._continuous is not None:
            self._continuous.close()
            self._continuous = None

    def work_once(self) -> bool:
        """The waiting job of one session, else one slice of continuous training: a job
        never waits for more than one slice. False when there was nothing to do."""
        return self.run_next() or self.train_continuous()

    def run_next(self) -> bool:
        """Run the job of the longest-waiting session, if any; True when one ran."""
        from groupwise.worker.job import job_of

        with self.db.read() as s:
            waiting = [row.id for row in worker_sessions(s) if self.serves(row.id)]
        for session_id in waiting:
            job = job_of(self.db, session_id)
            if job is not None:
                self.run_job(job)
                return True
        return False

    def train_continuous(self) -> bool:
        """One slice of continuous training (`worker.continuous`); True when one ran."""
        return self.continuous.step()

    def run_job(self, job: "Job") -> None:
        """Run one job; an exception marks the session failed with its message."""
        from groupwise.worker import finishing, jobs

        log.info("session %s: %s round %d", job.session_id, job.phase, job.round)
        reporter = ProgressReporter(self.db, job.session_id, job.phase, on_tick=_exit_if_orphaned)
        try:
            with reporter:
                progress = JobProgress(reporter)
                if job.phase == "preparing":
                    render = self._render_pool(job.settings.render_workers)
                    jobs.prepare(job, self.db, self.data_dir, render, progress)
                elif job.phase == "finishing":
                    finishing.finish(job, self.db, self.data_dir, progress)
                elif job.settings.training == "continuous":
                    training = self.continuous.take(job)
                    render = self._render_pool(job.settings.render_workers)
                    opened = False
                    try:
                        opened = jobs.train(
                            job, self.db, self.data_dir, progress, training.continuous, render,
                            training.staged,
                        )  # fmt: skip
                    finally:  # the run trains on into the round it opened, or closes
                        self.continuous.keep(job, training, opened)
                else:
                    jobs.train(job, self.db, self.data_dir, progress)
        except Exception as error:
            log.exception("session %s: %s round %d failed", job.session_id, job.phase, job.round)
            message = f"{job.phase} round {job.round} failed: {type(error).__name__}: {error}"
            with self.db.write() as s:
                mark_failed(s, job.session_id, job.phase, message[:2000])
            if job.phase == "preparing":  # a broken render pool must not fail the next job
                self._close_render_pools()

    def _render_pool(self, workers: int) -> "RenderPool":
        from groupwise.clips.render import RenderPool

        if workers not in self._render:
            self._render[workers] = RenderPool(workers)
        return self._render[workers]

    def _close_render_pools(self) -> None:
        for pool in self._render.values():
            pool.close()
        self._render.clear()
