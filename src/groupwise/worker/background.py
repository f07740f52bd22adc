"""The next round of a continuous session, prepared in a process of its own (issue 24).

Preparing a round — sampling the pool from the policy, DTW, the tree, the strategy's
queries, rendering the clips — took 11–23 s of the worker's main thread per Hopper round of
100 behaviours while PPO waited (a quarter of a 90-s round's PPO time under load). So the
worker writes a snapshot of the policy and the reward ensemble (`Run.save_policy`) and a
`Stager` process (one, "spawn", kept across rounds) samples, renders (in itself: one core
for the next round, one for PPO on a 2-core machine), publishes and stages the round from it
(`jobs.stage_next`, `jobs.publish_staged`), while PPO goes on in the worker. The snapshot is
deleted once staged.

The stager is a child of the worker and joins its process group, so ending the worker's
group ends it too (`worker.process`). A stager killed mid-way stages nothing: the round's
end then prepares the next round as in rounds mode.
"""

import logging
import multiprocessing
import os
import shutil
from collections.abc import Callable
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import TYPE_CHECKING, TypeVar

from groupwise.worker.jobs import Job

if TYPE_CHECKING:
    from groupwise.clips.render import RenderPool
    from groupwise.storage import Database

log = logging.getLogger(__name__)
T = TypeVar("T")

SNAPSHOT_DIR = "stage"
"""``checkpoints/stage``: the policy snapshot the next round is sampled from."""


class Stager:
    """One process that prepares next rounds from policy snapshots (module docstring)."""

    def __init__(self, database_url: str, data_dir: Path) -> None:
        self.data_dir = data_dir
        self._process = BackgroundProcess(database_url)

    def submit(self, job: Job, snapshot: Path, ppo_steps: int) -> "Future[None]":
        """Prepare and stage round `job.round + 1` from `snapshot` (`Run.save_policy`,
        sampled after `ppo_steps` PPO steps)."""
        return self._process.submit(_stage, job, self.data_dir, snapshot, ppo_steps)

    def close(self) -> None:
        self._process.close()


class BackgroundProcess:
    """One "spawn" process beside the worker, set up as the worker is (`process_db`), at a
    lower priority (`NICENESS`): the stager's, and the learning curve's evaluator
    (`curve.Evaluator`). One that died (killed for memory, say) is started again by the
    next `submit`; what it was doing fails with `BrokenProcessPool`."""

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
"""Added to the stager's and the evaluator's niceness: on a busy machine their work waits for
PPO and the web server instead of taking turns with them (the next round is ready minutes
ahead; a curve point may come a little later)."""

_db: "Database | None" = None
_render: "RenderPool | None" = None


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


def _stage(job: Job, data_dir: Path, snapshot: Path, ppo_steps: int) -> None:
    from groupwise.clips.render import RenderPool
    from groupwise.run.run import Run
    from groupwise.worker.jobs import publish_staged, stage_next

    global _render
    db = process_db()
    render = _render = _render or RenderPool(0)  # renders here (module docstring)
    try:
        with Run.create(job.settings.run_config(job.env)) as run:  # writes nothing
            run.load_policy(snapshot)
            offer = stage_next(job, run)
        publish_staged(job, offer, db, data_dir, render, ppo_steps)
    finally:
        shutil.rmtree(snapshot, ignore_errors=True)
