"""The worker's jobs: the two halves of a round, run apart in time because a person answers
in between (`groupwise.run.round`), on the session's `Run` in ``DIR/sessions/<session>/``.

prepare round r: the run as round r − 1 left it (`Run.restore`) → `begin_round` with the
    session's query strategy (the Groupwise-DM's group suggestions, or the Pairwise-DM's
    queries in pairwise mode) → `publishing.published_round`: clips into the shared store
    ``DIR/clips``, the tree and candidates (`pool.publish.publish_pool`), the queries as the
    page's suggestions and pairwise queue (`offers`) → `publishing.publish_offer` stores
    them in one transaction that opens the round.
train after round r: the run as round r − 1 left it → the round's stored judgements (not
    undone, each keyed by its place in the round) → `end_round`: pairs, dataset, reward fit,
    PPO for `ppo_steps_per_round`, evaluation, checkpoint and ``rounds.csv`` → round r + 1
    preparing, or finishing.
end a continuous round r (`worker.continuous` trained it while the person compared): its last fit
    brought up to date → round r + 1's pool cut from that run's latest rollouts
    (`pool.recent`, issue 39) and opened at once (`open_fresh`) → then round r committed
    (evaluation, checkpoint, record) while the person compares again.

A person and a simulated decision-maker therefore answer the same queries, and their
answers become training by the same function.
"""

import json
import logging
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from groupwise.behaviour import kernel_threads
from groupwise.clips.render import RenderPool
from groupwise.pool.dataset import dataset_sources
from groupwise.pool.recent import kept_tag, pool_ages
from groupwise.preferences.judgement import Judgement
from groupwise.rl.batch_envs import free_cores
from groupwise.run.continuous import ContinuousRound, cut_next
from groupwise.run.progress import RunCallback, as_callback
from groupwise.run.records import RoundRecord
from groupwise.run.round import begin_round, end_round, finish_round
from groupwise.storage import Database
from groupwise.storage.judgements import round_judgements
from groupwise.storage.lifecycle import advance_before_commit, finish_training, record_training
from groupwise.storage.models import utcnow
from groupwise.storage.rounds import PreparedRound, store_prepared_round
from groupwise.storage.sessions import get_round, round_directory
from groupwise.storage.training import add_point
from groupwise.types import IntArray
from groupwise.worker.job import Job, checkpoint_of, offered_queries, open_run, session_strategy
from groupwise.worker.progress import JobProgress
from groupwise.worker.publishing import (
    publish_offer,
    published_offer,
    published_round,
    sampled_at,
)

log = logging.getLogger(__name__)


@dataclass
class CutRound:
    """Round `round`'s pool cut from a continuous run's latest rollouts and published, not
    opened yet (`cut_fresh`; `open_cut` opens it)."""

    round: int
    prepared: PreparedRound
    steps: int
    """PPO steps of the policy when the pool was cut."""
    ages: IntArray
    """Each behaviour's age then, in PPO steps (`pool.recent.pool_ages`)."""
    pool_steps: int
    """The pool's place on the curve: PPO steps of the oldest policy its fresh behaviours
    come from (the kept policy's share aside, `run.kept_policy`)."""
    seconds: dict[str, float]
    """Wall seconds of the cut's parts: "sample" (what the rollouts lack), "cut" (the
    distances, the tree and the queries), "publish" (clips, posters, pool files)."""


def prepare(
    job: Job, db: Database, data_dir: Path, render: RenderPool, progress: JobProgress
) -> None:
    """Prepare round `job.round`'s offer and open the round (module docstring)."""
    settings = job.settings
    progress.on_phase("load", 0, 1)
    # nothing else of this worker runs meanwhile: the distances take the free cores
    # a recorded dataset's session has no agent: its pools are the dataset's windows, and
    # its settings (`SessionSettings.has_agent`) train no PPO, pre-train and evaluate nothing
    recorded = None if settings.dataset is None else dataset_sources(settings.dataset, job.env)
    with open_run(job, data_dir, job.round - 1) as run, kernel_threads(free_cores()):
        offer = begin_round(
            run,
            session_strategy(run.cfg, job.mode),
            settings.comparisons_per_round,
            n_queries=offered_queries(settings),
            callback=progress,
            sources=recorded,
        )
        steps = run.agent.num_timesteps
    prepared = published_round(
        data_dir, job.session_id, job.env, settings, offer.pool, offer.queries, render,
        progress, offer.sample_s, steps,
    )  # fmt: skip
    # the round's own pool position on the curve: round 0's is the policy's before any
    # point; a recorded dataset's session has no agent
    agent_steps = steps if recorded is None and job.round > 0 else None
    publish_offer(db, job.session_id, offer.pool.round, prepared, agent_steps)
    log.info(
        "session %s: round %d ready (%d behaviours)", job.session_id, job.round, len(offer.pool)
    )


def train(
    job: Job,
    db: Database,
    data_dir: Path,
    progress: JobProgress,
    continuous: ContinuousRound | None = None,
    render: RenderPool | None = None,
    staged: CutRound | None = None,
) -> bool:
    """End round `job.round` on its stored judgements and queue the next round or the final
    phase (module docstring); True when the next round opened here. With `continuous` (a
    continuous session's round, `worker.continuous`) the round's run is the one that trained while
    the person compared, the round adds no PPO steps of its own, and the run is left open
    for the caller (it trains on into the next round); with `render` too, the next round is
    cut from that run's rollouts and opens *before* the round is committed (`open_fresh`):
    the person compares again while the
    worker evaluates and checkpoints (a worker killed meanwhile commits it when it resumes:
    `worker.resume`). `staged`: the next round as cut before the round's end
    (`worker.continuous_round`), opened at once while no PPO step has run since."""
    r = job.round
    opened = False
    if continuous is None:
        record = commit_round(job, db, data_dir, progress)
    else:
        clock = OpeningClock()
        progress.on_phase("load", 0, 1)
        keyed = _judgements(db, job.session_id, r)
        fresh = staged is not None and staged.steps == continuous.run.agent.num_timesteps
        if render is not None and staged is not None and fresh:
            opened = open_cut(job, db, data_dir, continuous, staged, clock, staged=True)
        else:
            with clock("refit"):
                continuous.update(keyed, time.monotonic(), final=True)
            if render is not None:
                opened = open_fresh(job, db, data_dir, continuous, render, progress, clock)
        record = commit_continuous(continuous, keyed, job.elapsed_s, progress)
    checkpoint = checkpoint_of(job.session_id, r)
    stats = {**record.stats(), "pool_steps": pool_steps_of(db, data_dir, job.session_id, r)}
    with db.write() as s:
        if opened:
            record_training(s, job.session_id, r, checkpoint, stats)
        elif not finish_training(s, job.session_id, r, checkpoint, stats):
            log.warning("session %s moved on while round %d trained", job.session_id, r)
    log.info(
        "session %s: round %d trained on %d pairs (reward acc %.2f, true return %.1f)",
        job.session_id,
        r,
        record.pairs_total,
        record.reward_accuracy,
        record.true_return_mean,
    )
    return opened


def cut_fresh(
    job: Job,
    data_dir: Path,
    continuous: ContinuousRound,
    render: RenderPool,
    progress: JobProgress | None = None,
) -> CutRound:
    """Cut round `job.round + 1`'s pool from the latest rollouts of `continuous`'s run
    (`pool.recent.fresh_sources`: what they lack sampled from the policy) and publish it
    (clips, tree, candidates), while round `job.round` is still open."""
    settings, run, r = job.settings, continuous.run, job.round
    tick = time.perf_counter()
    # PPO waits for this: the distances take the free cores
    with kernel_threads(free_cores(FREE_PROBE_S)):
        offer = cut_next(
            run,
            session_strategy(run.cfg, job.mode),
            settings.comparisons_per_round,
            r + 1,
            n_queries=offered_queries(settings),
            callback=progress,
            judged=continuous.offer.pool,
        ).offer
    cut_s = time.perf_counter() - tick
    now = run.agent.num_timesteps
    tag = kept_tag(run.cfg.loop)
    ages = pool_ages(offer.pool, continuous.recorder, now, run.kept.sampled(tag))
    # the pool's place on the curve is its fresh behaviours' policy, not the kept share's
    sources = offer.pool.sources
    own = ages if sources is None else ages[sources != tag]
    pool_steps = now - int(own.max(initial=0))
    tick = time.perf_counter()
    prepared = published_round(
        data_dir, job.session_id, job.env, settings, offer.pool, offer.queries, render,
        progress, offer.sample_s, pool_steps, ages.tolist(),
    )  # fmt: skip
    seconds = {
        "sample": offer.sample_s,
        "cut": cut_s - offer.sample_s,
        "publish": time.perf_counter() - tick,
    }
    return CutRound(r + 1, prepared, now, ages, pool_steps, seconds)


def open_fresh(
    job: Job,
    db: Database,
    data_dir: Path,
    continuous: ContinuousRound,
    render: RenderPool,
    progress: JobProgress | None = None,
    clock: "OpeningClock | None" = None,
) -> bool:
    """Cut round `job.round + 1`'s pool now (`cut_fresh`) and open it (`open_cut`); False
    when that was the last round or the session moved on."""
    if job.round + 1 >= job.settings.rounds:
        return False
    clock = clock or OpeningClock()
    cut = cut_fresh(job, data_dir, continuous, render, progress)
    clock.seconds.update(cut.seconds)
    return open_cut(job, db, data_dir, continuous, cut, clock)


def open_cut(
    job: Job,
    db: Database,
    data_dir: Path,
    continuous: ContinuousRound,
    cut: CutRound,
    clock: "OpeningClock",
    staged: bool = False,
) -> bool:
    """Open round `cut.round` with its published pool in the transaction that queues round
    `job.round`'s commit, before that commit; False when the session moved on. Logs the
    pool's ages (PPO steps from the policy that played each behaviour to the policy now)
    and the wait since the round ended, and writes where that wait went (`clock`, started
    with the job) to the round's ``opening.json`` (`OpeningClock`); `staged`: the pool was
    cut before the round ended (`worker.continuous_round`), its parts no part
    of the wait."""
    run, r = continuous.run, job.round
    accuracy = None if continuous.report is None else continuous.report.validation_accuracy
    with clock("store"), db.write() as s:
        ended = get_round(s, job.session_id, r).closed_at
        opened = advance_before_commit(s, job.session_id, r) and store_prepared_round(
            s, job.session_id, cut.round, cut.prepared
        )
        if opened:
            add_point(
                s, job.session_id, round_index=cut.round, ppo_steps=cut.steps, true_return=None,
                pairs=len(run.dataset), reward_val_accuracy=accuracy, pool_steps=cut.pool_steps,
            )  # fmt: skip
    if opened:
        waited = (utcnow() - ended).total_seconds() if ended is not None else float("nan")
        path = data_dir / round_directory(job.session_id, cut.round) / OPENING_FILE
        clock.write(path, waited, cut.seconds if staged else None)
        ages = cut.ages
        log.info(
            "session %s: round %d opened %.1f s after round %d ended, %d behaviours%s: "
            "the latest rollouts' at most %s PPO steps old; with the kept policy's share, "
            "%s (median %s)",
            job.session_id,
            cut.round,
            waited,
            r,
            len(ages),
            " cut before the round ended" if staged else "",
            f"{cut.steps - cut.pool_steps:,}",
            f"{int(ages.min()) if len(ages) else 0:,}–{int(ages.max(initial=0)):,}",
            f"{int(np.median(ages)) if len(ages) else 0:,}",
        )
    return opened


FREE_PROBE_S = 0.05
"""Seconds `open_fresh` watches the cores to count the idle ones (`free_cores`), while the
person waits (its default, 0.2 s, was a tenth of the 2 s goal, issue 39)."""
OPENING_FILE = "opening.json"
"""Where the wait from End round to the next round's opening went, in a continuous
session's round directory (`OpeningClock.write`; `benchmarks.continuous` reads it)."""


class OpeningClock:
    """The wall seconds of each part of a continuous round's End-round job (`train`,
    `open_fresh`), and the CPU seconds of this process over the job."""

    def __init__(self) -> None:
        self.started = time.perf_counter()
        self.cpu = time.process_time()
        self.seconds: dict[str, float] = {}

    @contextmanager
    def __call__(self, part: str) -> Iterator[None]:
        tick = time.perf_counter()
        try:
            yield
        finally:
            self.seconds[part] = self.seconds.get(part, 0.0) + time.perf_counter() - tick

    def write(self, path: Path, waited: float, staged: dict[str, float] | None = None) -> None:
        """Write the parts to `path` as JSON with `waited`, the seconds from the round's end
        to its opening: what the job did not take of it ("before": the slice in progress
        and picking the job up); `staged`, the parts of a pool cut before the round ended
        (`CutRound.seconds`), apart as "staged_s"."""
        job = time.perf_counter() - self.started
        parts = {"before": waited - job, **self.seconds}
        parts["other"] = job - sum(self.seconds.values())
        record = {
            "waited_s": waited,
            "job_cpu_s": time.process_time() - self.cpu,
            "parts_s": {name: round(value, 4) for name, value in parts.items()},
            **(
                {}
                if staged is None
                else {"staged_s": {name: round(value, 4) for name, value in staged.items()}}
            ),
        }
        path.write_text(json.dumps(record, indent=1) + "\n")


def pool_steps_of(db: Database, data_dir: Path, session_id: str, round_index: int) -> int:
    """PPO steps of the policy that played round `round_index`'s pool (its oldest behaviour),
    from its ``pool.json`` (0 when it does not say)."""
    with db.read() as s:
        pool_dir = get_round(s, session_id, round_index).pool_dir
    sampled = None if pool_dir is None else sampled_at(data_dir / pool_dir)
    return sampled or 0


def commit_round(
    job: Job,
    db: Database,
    data_dir: Path,
    progress: RunCallback | None,
    continuous: ContinuousRound | None = None,
) -> RoundRecord:
    """Commit round `job.round` on its stored judgements: on `continuous`'s run
    (`commit_continuous`), left open for the next round; else `end_round` on the run as the
    round before left it (`ppo_steps_per_round`), closed."""
    settings, r = job.settings, job.round
    if progress is not None:
        progress.on_phase("load", 0, 1)
    keyed = _judgements(db, job.session_id, r)
    if continuous is not None:
        return commit_continuous(continuous, keyed, job.elapsed_s, progress)
    with db.read() as s:
        pool_dir = get_round(s, job.session_id, r).pool_dir
    if pool_dir is None:
        raise FileNotFoundError(f"round {r} has no pool directory")
    offer = published_offer(data_dir / pool_dir, r, settings.comparisons_per_round, job.mode)
    with open_run(job, data_dir, r - 1) as run:
        return end_round(
            run,
            offer,
            [judgement for _, judgement in keyed],
            settings.ppo_steps_per_round,
            keys=[key for key, _ in keyed],
            feedback_s=job.elapsed_s,
            callback=progress,
        )


def commit_continuous(
    continuous: ContinuousRound,
    keyed: Sequence[tuple[int, Judgement]],
    feedback_s: float,
    progress: RunCallback | None,
) -> RoundRecord:
    """Commit a continuous round on the run that trained it: its last fit brought up to
    date (`ContinuousRound.update`, as the headless continuous round ends: no PPO steps, no second
    fit of the same pairs), evaluation, checkpoint; its mid-round checkpoint dropped."""
    continuous.update(keyed, time.monotonic(), final=True)
    continuous.timer.seconds["feedback_s"] = feedback_s
    record = finish_round(
        continuous.run,
        continuous.offer,
        [judgement for _, judgement in keyed],
        continuous.report,
        continuous.timer,
        as_callback(progress),
        asked=None,
    )
    continuous.run.drop_mid_round()
    return record


def _judgements(db: Database, session_id: str, round_index: int) -> list[tuple[int, Judgement]]:
    with db.read() as s:
        return round_judgements(s, session_id, round_index)
