"""Run a simulated study: every (env, DM, seed) cell as an independent process (SPEC §8).

A cell is one `run_session` into ``OUT/cells/{env}/{dm}/seed-{k}/`` (``OUT/{ablation}/...``
for a cell of an ablation, `ablations.ABLATIONS`). Cells run on this machine in a process
pool, one worker per core by default, or on a Ray cluster. Pools use the "spawn" start
method: numba (the DTW of the group decision-makers) leaves forked children unable to run it
again.

Rerunning a study is how it resumes: a cell whose ``done.json`` exists is skipped, and an
unfinished one continues from its last round checkpoint (`run_session(..., resume=True)`), so
a killed study loses at most one round per running cell. On Ray, a task lost with its node is
retried and resumes the same way; the study directory must then be on a filesystem every node
sees.
"""

import logging
import math
import multiprocessing
import os
import time
import traceback
from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from tqdm.auto import tqdm

from groupwise.config import RunConfig
from groupwise.study.simulation.ablations import ABLATIONS
from groupwise.study.simulation.cells import MAIN, Cell, is_done, mark_done, read_plan, write_plan
from groupwise.study.simulation.profiles import StudyProfile

log = logging.getLogger(__name__)

RAY_HINT = "pip install groupwise[ray]"
WORKER_ENV = {"NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
"""Environment of every worker: one cell, one core. With a worker per core, a DTW kernel
or OpenMP region that spreads over every core only contends with the other workers. numba
reads NUMBA_NUM_THREADS when it is imported, so it is set before the worker starts."""


class StudyMismatchError(ValueError):
    """The study directory was started with another profile."""


class RayUnavailableError(RuntimeError):
    """`--ray` was asked for but Ray is not installed."""


@dataclass(frozen=True)
class StudySpec:
    """What to run: the cross product envs × DMs × seeds 0 … seeds−1 of one profile."""

    profile: StudyProfile
    envs: tuple[str, ...]
    dms: tuple[str, ...]
    seeds: int
    ablations: tuple[str, ...] = ()
    """Also run every cell under each of these ablations (keys of `ABLATIONS`; ``capped`` is
    SPEC §8's capped pairs)."""

    def __post_init__(self) -> None:
        unknown = [name for name in self.ablations if name not in ABLATIONS]
        if unknown:
            raise ValueError(f"unknown ablation {unknown[0]!r}; choose from {', '.join(ABLATIONS)}")

    def cells(self) -> list[Cell]:
        conditions = (MAIN, *dict.fromkeys(self.ablations))
        return [
            Cell(env, dm, seed, condition)
            for condition in conditions
            for env in self.envs
            for dm in self.dms
            for seed in range(self.seeds)
        ]


@dataclass(frozen=True)
class CellJob:
    """One cell with everything a worker needs to run it."""

    cell: Cell
    config: RunConfig
    directory: Path
    """Absolute, so that a worker with another working directory finds it."""


@dataclass(frozen=True)
class CellOutcome:
    """How one cell went."""

    cell: Cell
    status: Literal["done", "skipped", "failed"]
    """``done``: finished now; ``skipped``: finished before; ``failed``: raised."""
    seconds: float = 0.0
    """Wall time of this run of the cell (a resumed cell counts only its last part)."""
    final_return: float = math.nan
    """True return after the last row."""
    pairs_total: int = 0
    error: str | None = None
    """``Type: message`` of the exception of a failed cell."""
    details: str | None = None
    """The traceback of a failed cell."""


@dataclass(frozen=True)
class StudySummary:
    outcomes: tuple[CellOutcome, ...]

    def count(self, status: str) -> int:
        return sum(o.status == status for o in self.outcomes)

    @property
    def failed(self) -> tuple[CellOutcome, ...]:
        return tuple(o for o in self.outcomes if o.status == "failed")


def plan_jobs(spec: StudySpec, out: Path) -> list[CellJob]:
    """Every cell of `spec` as a job, the largest PPO budgets first (better packing).

    Raises:
        ValueError: a profile value `LoopConfig` rejects.
    """
    root = out.resolve()
    jobs = [
        CellJob(
            cell,
            spec.profile.run_config(cell.env, cell.dm, cell.seed, cell.ablation),
            cell.directory(root),
        )
        for cell in spec.cells()
    ]
    return sorted(jobs, key=lambda j: (-spec.profile.budget(j.cell.env).total, j.cell))


def run_cell(job: CellJob) -> CellOutcome:
    """Run (or resume) one cell to the end in this process and mark it done.

    Never raises for a failing session: the exception comes back in the outcome, so one
    broken cell does not stop the study.
    """
    if is_done(job.directory):
        return CellOutcome(job.cell, "skipped")
    import torch  # in the worker only: the parent never needs it

    from groupwise.run.headless import run_session

    # Tiny nets: more intra-op threads only contend with the other workers (see cli.py).
    torch.set_num_threads(1)
    start = time.perf_counter()
    try:
        records = run_session(job.config, job.directory, resume=True, show_progress=False)
    except Exception as error:
        return CellOutcome(
            job.cell,
            "failed",
            seconds=time.perf_counter() - start,
            error=f"{type(error).__name__}: {error}",
            details=traceback.format_exc(),
        )
    seconds = time.perf_counter() - start
    last = records[-1]
    mark_done(
        job.directory,
        {
            "cell": job.cell.to_json(),
            "rows": len(records),
            "seconds": seconds,
            "final_true_return": last.true_return_mean,
            "pairs_total": last.pairs_total,
            "finished": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        },
    )
    return CellOutcome(
        job.cell, "done", seconds, float(last.true_return_mean), int(last.pairs_total)
    )


def run_study(
    spec: StudySpec,
    out: Path,
    workers: int | None = None,
    backend: Literal["local", "ray"] = "local",
    ray_address: str | None = None,
    show_progress: bool = True,
    on_cell: Callable[[CellOutcome], None] | None = None,
) -> StudySummary:
    """Run every unfinished cell of `spec` into study directory `out`.

    Args:
        workers: parallel cells on this machine (default: one per core); with Ray and no
            `ray_address`, the CPUs the local Ray gets; ignored on an existing cluster.
        backend: ``local`` (a spawn process pool) or ``ray``.
        ray_address: the cluster to join; None starts a local Ray.
        on_cell: called in this process with each outcome, skipped cells included.

    A script that calls this must guard its entry point (``if __name__ == "__main__":``):
    spawned workers import the main module again.

    Raises:
        StudyMismatchError: `out` was started with another profile.
        RayUnavailableError: `backend="ray"` and Ray is not installed.
    """
    plan = read_plan(out)
    if plan is not None and plan["profile"] != spec.profile.name:
        raise StudyMismatchError(
            f"{out} holds a study with profile {plan['profile']!r}; "
            f"use --profile {plan['profile']} or another --out"
        )
    jobs = plan_jobs(spec, out)
    out.mkdir(parents=True, exist_ok=True)
    write_plan(out, spec.profile.name, spec.cells())
    workers = workers or os.cpu_count() or 1

    outcomes: list[CellOutcome] = []
    before = {job.cell for job in jobs if is_done(job.directory)}
    todo = [job for job in jobs if job.cell not in before]
    bar = tqdm(total=len(jobs), desc="cells", unit="cell", disable=not show_progress)

    def finished(outcome: CellOutcome) -> None:
        outcomes.append(outcome)
        _log_outcome(outcome)
        bar.update(1)
        if on_cell is not None:
            on_cell(outcome)

    for cell in sorted(before):
        finished(CellOutcome(cell, "skipped"))
    log.info(
        "%d cells: %d finished before, %d to run on %s",
        len(jobs),
        len(before),
        len(todo),
        backend if backend == "local" else f"ray ({ray_address or 'local'})",
    )
    try:
        if todo and backend == "ray":
            _run_on_ray(todo, ray_address, workers, finished)
        elif todo:
            _run_in_pool(todo, workers, finished)
    finally:
        bar.close()
    return StudySummary(tuple(outcomes))


def _run_in_pool(
    jobs: list[CellJob], workers: int, finished: Callable[[CellOutcome], None]
) -> None:
    context = multiprocessing.get_context("spawn")
    pending: dict[Future[CellOutcome], CellJob] = {}
    # spawned workers inherit the environment; it is restored when the pool is gone
    with _environment(WORKER_ENV):
        pool = ProcessPoolExecutor(max_workers=min(workers, len(jobs)), mp_context=context)
        try:
            pending = {pool.submit(run_cell, job): job for job in jobs}
            while pending:
                done, _ = wait(pending, return_when=FIRST_COMPLETED)
                for future in done:
                    job = pending.pop(future)
                    try:
                        outcome = future.result()
                    except Exception as error:  # a worker killed from outside (OOM, signal)
                        outcome = _crashed(job, error)
                    finished(outcome)
        finally:
            pool.shutdown(wait=not pending, cancel_futures=True)


def _run_on_ray(
    jobs: list[CellJob],
    address: str | None,
    workers: int,
    finished: Callable[[CellOutcome], None],
) -> None:
    try:
        import ray
    except ImportError:
        raise RayUnavailableError(f"Ray is not installed: {RAY_HINT}") from None
    started = False
    if not ray.is_initialized():
        if address:
            ray.init(address=address, logging_level=logging.WARNING, log_to_driver=False)
        else:
            ray.init(
                num_cpus=workers,
                include_dashboard=False,
                logging_level=logging.WARNING,
                log_to_driver=False,
            )
        started = True
    try:
        # A task lost with its worker is retried; `run_cell` resumes from the checkpoint.
        remote = ray.remote(num_cpus=1, max_retries=3, runtime_env={"env_vars": WORKER_ENV})(
            run_cell
        )
        pending = {remote.remote(job): job for job in jobs}
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            for ref in ready:
                job = pending.pop(ref)
                try:
                    outcome = ray.get(ref)
                except Exception as error:
                    outcome = _crashed(job, error)
                finished(outcome)
    finally:
        if started:
            ray.shutdown()


@contextmanager
def _environment(values: dict[str, str]) -> Iterator[None]:
    saved = {key: os.environ.get(key) for key in values}
    os.environ.update(values)
    try:
        yield
    finally:
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


def _crashed(job: CellJob, error: BaseException) -> CellOutcome:
    return CellOutcome(
        job.cell,
        "failed",
        error=f"worker lost: {type(error).__name__}: {error}",
        details="".join(traceback.format_exception(error)),
    )


def _log_outcome(outcome: CellOutcome) -> None:
    if outcome.status == "done":
        log.info(
            "%s finished in %.0f s: true return %.2f, %d preference pairs",
            outcome.cell.label,
            outcome.seconds,
            outcome.final_return,
            outcome.pairs_total,
        )
    elif outcome.status == "failed":
        log.error("%s failed: %s", outcome.cell.label, outcome.error)
        log.debug("%s", outcome.details)
    else:
        log.debug("%s already finished", outcome.cell.label)
