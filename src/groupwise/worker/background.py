"""The worker's background processes: one "spawn" process each beside the worker, at a
lower priority, for work PPO must not wait for (the learning curve's evaluations,
`curve.Evaluator`).

A background process is a child of the worker and joins its process group, so ending the
worker's group ends it too (`worker.process`).
"""

import logging
import multiprocessing
import os
from collections.abc import Callable
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import TYPE_CHECKING, TypeVar

if TYPE_CHECKING:
    from groupwise.storage import Database

log = logging.getLogger(__name__)
T = TypeVar("T")


class BackgroundProcess:
    """One "spawn" process beside the worker, set up as the worker is (`process_db`), at a
    lower priority (`NICENESS`): the learning curve's evaluator (`curve.Evaluator`). One
    that died (killed for memory, say) is started again by the next `submit`; what it was
    doing fails with `BrokenProcessPool`."""

    def __init__(self, database_url: str) -> None:
        self.database_url = database_url
        self._pool = self._spawn()

    def submit(self, fn: Callable[..., T], /, *args: object) -> "Future[T]":
        try:
            return self._pool.submit(fn, *args)
        except BrokenProcessPool:
            log.warning("a background process of the worker died; starting another")
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = self._spawn()
            return self._pool.submit(fn, *args)

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)

    def _spawn(self) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(
            max_workers=1,
            mp_context=multiprocessing.get_context("spawn"),
            initializer=_start,
            initargs=(self.database_url, logging.getLogger("groupwise").getEffectiveLevel()),
        )


NICENESS = 5
"""Added to a background process's niceness: on a busy machine its work waits for PPO and
the web server instead of taking turns with them (a curve point may come a little later)."""

_db: "Database | None" = None


def process_db() -> "Database":
    """The database connection of a `BackgroundProcess`."""
    assert _db is not None, "this process is not a BackgroundProcess"
    return _db


def _start(database_url: str, log_level: int) -> None:
    """A process's start: a lower priority than the worker's PPO and the web server
    (`NICENESS`), one thread per numeric library (the worker's environment says so for
    numba and OpenMP), its log, its database connection."""
    import torch

    from groupwise.behaviour import set_kernel_threads
    from groupwise.storage import Database

    global _db
    os.nice(NICENESS)
    torch.set_num_threads(1)
    set_kernel_threads(1)
    logging.basicConfig(
        level=logging.WARNING, format="%(asctime)s %(levelname)s %(name)s: %(message)s"
    )
    logging.getLogger("groupwise").setLevel(log_level)
    _db = Database(database_url, pool_size=1)
