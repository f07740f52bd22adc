"""The server's side of the training workers: start them, watch them, report a death.

One worker process by default; with `WorkerConfig.processes` N, worker k serves the
sessions whose id `process.shard_of` maps to k (a stable hash), and each check below runs
for every shard.

`Supervisor.check()` runs every `WorkerConfig.supervisor_poll_s` in the app's lifespan task (on
a thread, so it never blocks the event loop). Each check:

1. when the worker process has died (killed, out of memory), marks the sessions it was
   working on ``failed`` with "the training worker stopped (exit code …)"; sessions still
   queued behind them stay queued;
2. closes rounds whose time budget is used up (the timer is also checked on every read);
3. starts a worker when there is work and none is running, e.g. after `POST /retry`
   re-queued a failed step, at startup for sessions a previous server left mid-step, or
   for an open round that trains continuously (a killed worker's training resumes from
   its mid-round checkpoint at once, not when the round ends).
"""

import asyncio
import contextlib
import logging
import multiprocessing
import os
import threading
from dataclasses import dataclass
from multiprocessing.process import BaseProcess
from pathlib import Path

from groupwise.storage import Database
from groupwise.storage.lifecycle import close_if_due, mark_failed
from groupwise.storage.phases import READY
from groupwise.storage.sessions import sessions_in, training_open_rounds, worker_sessions
from groupwise.storage.timer import round_due
from groupwise.worker.process import THREAD_ENV, kill_group, shard_of, worker_main

log = logging.getLogger(__name__)

QUEUED = "queued"
"""The progress phase of a session that no worker has started on yet."""


@dataclass(frozen=True)
class WorkerConfig:
    """Where the worker finds its work and how often the two sides look."""

    db_url: str
    """The database the server and the worker share."""
    data_dir: Path
    """The data directory (clips, sessions' runs)."""
    worker_poll_s: float = 0.25
    """How often an idle worker reads the database for work."""
    supervisor_poll_s: float = 0.25
    """How often the server checks that its worker lives (and starts one when work waits)."""
    processes: int = 1
    """Training worker processes (``serve --training-workers``): each serves the sessions
    `process.shard_of` gives it, so sessions on different workers train on different
    cores; the sessions of one worker take turns."""


class Supervisor:
    """Owns the worker processes (`WorkerConfig.processes`, each serving a shard of the
    sessions). Thread-safe: checks run on worker threads of the app."""

    def __init__(self, db: Database, config: WorkerConfig) -> None:
        if config.processes < 1:
            raise ValueError(f"processes must be >= 1, got {config.processes}")
        self.db = db
        self.config = config
        self._lock = threading.Lock()
        self._processes: dict[int, BaseProcess] = {}
        self._stopping = False
        self._loop: asyncio.AbstractEventLoop | None = None
        self._wake: asyncio.Event | None = None

    @property
    def worker_pids(self) -> list[int]:
        """The running workers' process ids, by shard."""
        running = sorted(self._processes.items())
        return [p.pid for _, p in running if p.pid is not None and p.is_alive()]

    @property
    def worker_pid(self) -> int | None:
        """A running worker's process id (the first shard's; None when none runs)."""
        return next(iter(self.worker_pids), None)

    def check(self) -> None:
        """One round of supervision (module docstring), for every shard."""
        with self._lock:
            if self._stopping:
                return
            for shard, process in list(self._processes.items()):
                if not process.is_alive():
                    del self._processes[shard]
                    if process.pid is not None:
                        kill_group(process.pid)  # render processes it may have left
                    self._report_death(shard, process.exitcode)
            self._close_due_rounds()
            for shard in self._waiting_shards():
                if shard not in self._processes:
                    self._start(shard)

    async def run(self) -> None:
        """Check every `supervisor_poll_s` (or at once when woken) until cancelled."""
        self._loop = asyncio.get_running_loop()
        self._wake = asyncio.Event()
        while True:
            try:
                await asyncio.to_thread(self.check)
            except Exception:  # a failed check (e.g. the disk is full) must not end supervision
                log.exception("supervisor check failed")
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._wake.wait(), self.config.supervisor_poll_s)
            self._wake.clear()

    def ensure_worker_soon(self) -> None:
        """Wake the supervision loop (from any thread): new work may need a worker started,
        e.g. after `POST /retry`. Does nothing when no loop runs (no worker configured)."""
        loop, wake = self._loop, self._wake
        if loop is not None and wake is not None and not loop.is_closed():
            loop.call_soon_threadsafe(wake.set)

    def stop(self, timeout_s: float = 5.0) -> None:
        """Stop the workers (on server shutdown); their steps re-run on the next start."""
        with self._lock:
            self._stopping = True
            processes, self._processes = list(self._processes.values()), {}
        for process in processes:
            process.terminate()
        for process in processes:
            process.join(timeout_s)
            if process.pid is not None:
                kill_group(process.pid)  # the worker if still alive, and its render processes
            process.join(timeout_s)

    def _start(self, shard: int) -> None:
        context = multiprocessing.get_context("spawn")
        process = context.Process(
            target=worker_main,
            args=(
                self.config.db_url,
                str(self.config.data_dir),
                self.config.worker_poll_s,
                logging.getLogger("groupwise").getEffectiveLevel(),
                (shard, self.config.processes),
            ),
            name=f"groupwise-worker-{shard}",
            daemon=False,  # it starts render processes of its own
        )
        saved = {key: os.environ.get(key) for key in THREAD_ENV}
        os.environ.update(THREAD_ENV)
        try:
            process.start()
        finally:
            for key, value in saved.items():
                if value is None:
                    os.environ.pop(key, None)
                else:
                    os.environ[key] = value
        self._processes[shard] = process
        log.info("training worker %d started (pid %s)", shard, process.pid)

    def _report_death(self, shard: int, exit_code: int | None) -> None:
        message = f"the training worker stopped (exit code {exit_code})"
        log.error("%s (shard %d)", message, shard)
        with self.db.write() as s:
            for session in worker_sessions(s):
                if session.progress_phase != QUEUED and self._shard(session.id) == shard:
                    mark_failed(s, session.id, session.phase, message)

    def _close_due_rounds(self) -> None:
        with self.db.read() as s:
            due = [row.id for row in sessions_in(s, (READY,)) if round_due(row)]
        for session_id in due:
            with self.db.write() as s:
                close_if_due(s, session_id)

    def _waiting_shards(self) -> set[int]:
        """The shards with work: a session waits for a job, or an open round trains
        continuously (after a killed worker, its training resumes without waiting for the
        round's end)."""
        with self.db.read() as s:
            rows = worker_sessions(s) + training_open_rounds(s)
            return {self._shard(row.id) for row in rows}

    def _shard(self, session_id: str) -> int:
        return shard_of(session_id, self.config.processes)
