"""The server's side of the training worker: start it, watch it, report its death.

`Supervisor.check()` runs every `WorkerConfig.supervisor_poll_s` in the app's lifespan task (on
a thread, so it never blocks the event loop). Each check:

1. when the worker process has died (killed, out of memory), marks the sessions it was
   working on ``failed`` with "the training worker stopped (exit code …)"; sessions still
   queued behind them stay queued;
2. closes rounds whose time budget is used up (the timer is also checked on every read);
3. starts a worker when there is work and none is running, e.g. after `POST /retry`
   re-queued a failed step, at startup for sessions a previous server left mid-step, or
   for an open round that trains continuously (a killed worker's training resumes from
   its live checkpoint at once, not when the round ends).
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
from groupwise.worker.process import THREAD_ENV, kill_group, worker_main

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


class Supervisor:
    """Owns the worker process. Thread-safe: checks run on worker threads of the app."""

    def __init__(self, db: Database, config: WorkerConfig) -> None:
        self.db = db
        self.config = config
        self._lock = threading.Lock()
        self._process: BaseProcess | None = None
        self._stopping = False
        self._loop: asyncio.AbstractEventLoop | None = None
        self._wake: asyncio.Event | None = None

    @property
    def worker_pid(self) -> int | None:
        """The running worker's process id (None when none runs)."""
        process = self._process
        return process.pid if process is not None and process.is_alive() else None

    def check(self) -> None:
        """One round of supervision (module docstring)."""
        with self._lock:
            if self._stopping:
                return
            process = self._process
            if process is not None and not process.is_alive():
                self._process = None
                if process.pid is not None:
                    kill_group(process.pid)  # render processes it may have left
                self._report_death(process.exitcode)
            self._close_due_rounds()
            if self._process is None and self._has_work():
                self._start()

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
        """Stop the worker (on server shutdown); its step re-runs on the next start."""
        with self._lock:
            self._stopping = True
            process, self._process = self._process, None
        if process is None:
            return
        process.terminate()
        process.join(timeout_s)
        if process.pid is not None:
            kill_group(process.pid)  # the worker if it is still alive, and its render processes
        process.join(timeout_s)

    def _start(self) -> None:
        context = multiprocessing.get_context("spawn")
        process = context.Process(
            target=worker_main,
            args=(
                self.config.db_url,
                str(self.config.data_dir),
                self.config.worker_poll_s,
                logging.getLogger("groupwise").getEffectiveLevel(),
            ),
            name="groupwise-worker",
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
        self._process = process
        log.info("training worker started (pid %s)", process.pid)

    def _report_death(self, exit_code: int | None) -> None:
        message = f"the training worker stopped (exit code {exit_code})"
        log.error(message)
        with self.db.write() as s:
            for session in worker_sessions(s):
                if session.progress_phase != QUEUED:
                    mark_failed(s, session.id, session.phase, message)

    def _close_due_rounds(self) -> None:
        with self.db.read() as s:
            due = [row.id for row in sessions_in(s, (READY,)) if round_due(row)]
        for session_id in due:
            with self.db.write() as s:
                close_if_due(s, session_id)

    def _has_work(self) -> bool:
        """A session waits for a job, or an open round trains continuously (after a killed
        worker, its training resumes without waiting for the round's end)."""
        with self.db.read() as s:
            return bool(worker_sessions(s)) or bool(training_open_rounds(s))
