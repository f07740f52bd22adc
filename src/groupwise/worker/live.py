"""Continuous training in the app (issue 24): the worker trains an open round's policy while
the person compares, instead of idling until the round ends.

Whenever no phase job waits (`process.Worker`), `LiveSessions.step` gives one open
session with ``training: "continuous"`` one slice, the sessions taking turns: its
judgements read from the database (`round_judgements`: undone ones left out, each keyed by
its place in the round), the reward ensemble refitted when due (`run.continuous.LiveRound`:
20 changed pairs or 60 s), then one PPO rollout on the latest fit — so the reward PPO sees
changes only between rollouts. Every `CHECKPOINT_S` seconds the policy and the ensemble
go to ``checkpoints/live`` (`Run.save_live`). The database holds every acknowledged
judgement, so a killed worker loses none: the next one resumes the round from its live
checkpoint and refits on all of them.

The page sees the agent learn (`worker.curve`): each refit stores a point of the session's
learning curve (PPO steps, pairs, validation accuracy), and so does each evaluation of the
greedy policy's true return, the first before the round's first rollout, then whenever the
last one has finished and the slices have trained long enough (`curve.EVAL_MIN_S`,
`curve.EVAL_COST`). Evaluations run on a snapshot of the policy in a process of their own
(`curve.Evaluator`), so PPO does not wait for them. Every `ACCOUNT_S` seconds a log line
says where the worker's time went (PPO, refits, reads, checkpoints, ...).

The next round is prepared ahead, `stage_after_s` seconds into the round (a session
setting), from a snapshot of the policy as it was then, in the stager process
(`worker.staging`) while PPO goes on here, and waits in the database (`storage.staging`).
The round's end (the person, its budget or its timer) opens it in the same transaction, so
"End round" answers with the next round; this worker then commits the ended round on the
run that trained all along (`end_round` with no PPO steps of its own: final fit,
evaluation, checkpoint) before its next slice. A worker killed in between commits that
round when it resumes. A round ended before its successor was staged goes to the training
job (`take`), which waits for the staging, opens it and commits; a round ended before the
staging began has its next pool sampled then, as in rounds mode.
"""

import dataclasses
import logging
import math
import shutil
import time
from collections import defaultdict
from collections.abc import Callable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from groupwise.run.checkpoint import CHECKPOINTS
from groupwise.run.continuous import LiveRound
from groupwise.run.run import Run
from groupwise.run.streams import round_streams
from groupwise.storage import Database
from groupwise.storage.judgements import round_judgements
from groupwise.storage.lifecycle import record_training, uncommitted_round
from groupwise.storage.phases import READY, TRAINING
from groupwise.storage.sessions import get_round, sessions_in, settings_of
from groupwise.storage.training import add_point
from groupwise.worker import curve
from groupwise.worker.jobs import (
    Job,
    checkpoint_of,
    commit_round,
    committed_record,
    open_run,
    published_offer,
    sampled_at,
)
from groupwise.worker.staging import SNAPSHOT_DIR, Stager

log = logging.getLogger(__name__)

CHECKPOINT_S = 30.0
"""Seconds between a continuous round's live checkpoints."""
CONTINUOUS = "continuous"
SLOW_SLICE_S = 1.5
"""A slice longer than this is logged: a training job waits for the slice in progress."""
ACCOUNT_S = 60.0
"""Seconds between the log lines that say where a continuous round's worker time went."""


@dataclass
class LiveTraining:
    """One session's round being trained continuously in this worker."""

    session_id: str
    round: int
    run: Run
    live: LiveRound
    checkpointed: float
    """`time.monotonic()` of the last live checkpoint."""
    started: float
    """`time.monotonic()` when this worker took the round up."""
    pool_steps: int
    """PPO steps of the policy that sampled the round's pool."""
    staged: "Future[None] | None" = None
    """The next round's offer being published ahead (on `LiveSessions`' staging thread),
    or published; None before."""
    trained_s: float = 0.0
    """Seconds this worker's PPO slices of the round took."""
    evaluated_s: float | None = None
    """`trained_s` at the last evaluation; None before the first."""
    eval_s: float = 0.0
    """Seconds the last finished evaluation took."""
    evaluating: "Future[float] | None" = None
    """The evaluation in the evaluator process (`curve.Evaluator`), until it is seen done."""
    spent: defaultdict[str, float] = dataclasses.field(default_factory=lambda: defaultdict(float))
    """Worker seconds by activity since `accounted` (`timed`): what is not PPO is PPO's
    loss, logged every `ACCOUNT_S` seconds."""
    accounted: float = dataclasses.field(default_factory=time.monotonic)

    @contextmanager
    def timed(self, activity: str) -> Iterator[None]:
        """Count the seconds of the block as `activity` in `spent`."""
        tick = time.perf_counter()
        try:
            yield
        finally:
            self.spent[activity] += time.perf_counter() - tick

    def account(self) -> None:
        """Log where the worker's time went since the last such line, once `ACCOUNT_S`
        seconds have passed (the rest of the wall time: other sessions, jobs, waiting)."""
        wall = time.monotonic() - self.accounted
        if wall < ACCOUNT_S:
            return
        self.spent["other"] = wall - sum(self.spent.values())
        parts = ", ".join(
            f"{name} {seconds:.1f} s ({seconds / wall:.0%})"
            for name, seconds in sorted(self.spent.items(), key=lambda item: -item[1])
        )
        log.info(
            "session %s round %d, the last %.0f s: %s", self.session_id, self.round, wall, parts
        )
        self.spent.clear()
        self.accounted = time.monotonic()


class LiveSessions:
    """The worker's continuous rounds, one `LiveTraining` per open session (module
    docstring)."""

    def __init__(
        self, db: Database, data_dir: Path, serves: Callable[[str], bool] = lambda _: True
    ) -> None:
        self.db = db
        self.data_dir = data_dir
        self.serves = serves
        """Whether this worker serves a session (`process.Worker.serves`)."""
        self._live: dict[str, LiveTraining] = {}
        self._turns: dict[str, int] = {}
        self._turn = 0
        self._stager: Stager | None = None
        self._evaluator: curve.Evaluator | None = None
        self._staging = ThreadPoolExecutor(max_workers=1, thread_name_prefix="staging")
        """Waits on the stager process (`worker.staging`), one next round at a time."""
        self._broken: dict[str, int] = {}
        """Sessions whose continuous training failed, and the round: left alone until the
        round ends (its training job then tries once more and fails visibly if it must)."""

    def step(self) -> bool:
        """One slice of training for the open continuous session whose turn it is (a session
        with nothing to learn from yet passes its turn on); False when none trained (the
        worker then sleeps)."""
        open_jobs, ending = self._continuous_sessions()
        jobs = [job for job in open_jobs if self._broken.get(job.session_id) != job.round]
        # a round just ended keeps its run for the training job
        for stale in set(self._live) - {job.session_id for job in jobs} - ending:
            self._live.pop(stale).run.close()
        for job in sorted(jobs, key=lambda j: self._turns.get(j.session_id, -1)):
            self._turn += 1
            self._turns[job.session_id] = self._turn
            tick = time.perf_counter()
            try:
                trained = self._slice(job)
            except Exception:
                log.exception(
                    "session %s: continuous training of round %d failed",
                    job.session_id,
                    job.round,
                )
                self._broken[job.session_id] = job.round
                if (training := self._live.pop(job.session_id, None)) is not None:
                    training.run.close()
                return True
            if (took := time.perf_counter() - tick) > SLOW_SLICE_S:
                log.info("session %s: a slice took %.1f s", job.session_id, took)
            if trained:
                return True
        return False

    def _slice(self, job: Job) -> bool:
        """Refit when due and train one rollout; False when the round has no pairs yet."""
        training = self._training(job)
        with training.timed("reads"), self.db.read() as s:
            keyed = round_judgements(s, job.session_id, job.round)
        with training.timed("refits"):
            refitted = training.live.update(keyed, time.monotonic())
        run = training.run
        if not len(run.dataset):  # PPO starts with the round's first pairs
            training.spent.clear()  # waiting for them is no loss of PPO's: not accounted
            training.accounted = time.monotonic()
            return False
        if refitted or training.evaluated_s is None:
            self._point(training, refit=refitted, evaluate=training.evaluated_s is None)
        tick = time.perf_counter()
        with training.timed("PPO"):
            training.live.learn(run.ppo.rollout_steps)
        training.trained_s += time.perf_counter() - tick
        if self._evaluation_due(training):
            self._point(training, refit=False, evaluate=True)
        if time.monotonic() - training.checkpointed >= CHECKPOINT_S:
            with training.timed("checkpoints"):
                run.save_live(job.round)
            training.checkpointed = time.monotonic()
        with training.timed("staging"):
            self._stage(job, training)
        training.account()
        return True

    def _stage(self, job: Job, training: LiveTraining) -> None:
        """Prepare the next round ahead once the round trained `stage_after_s`: from a
        snapshot of the policy, in the stager process (`worker.staging`), while the slices
        go on."""
        last = job.round + 1 >= job.settings.rounds
        waited = time.monotonic() - training.started
        if training.staged is not None or last or waited < job.settings.stage_after_s:
            return
        snapshot = training.run.directory / CHECKPOINTS / SNAPSHOT_DIR
        shutil.rmtree(snapshot, ignore_errors=True)
        snapshot.mkdir(parents=True)
        training.run.save_policy(snapshot)
        steps = training.run.agent.num_timesteps
        training.staged = self._staging.submit(self._stage_in_process, job, snapshot, steps)

    def _stage_in_process(self, job: Job, snapshot: Path, steps: int) -> None:
        if self._stager is None:
            self._stager = Stager(self.db.url, self.data_dir)
        self._stager.submit(job, snapshot, steps).result()

    def _point(self, training: LiveTraining, *, refit: bool, evaluate: bool) -> None:
        """Store a point of the learning curve: with `refit`, the steps and the fit now; then,
        with `evaluate`, hand the point with a snapshot of the greedy policy to the evaluator
        process, which stores it with the policy's true return when it has it
        (`curve.Evaluator`)."""
        run, report = training.run, training.live.report
        accuracy = None if report is None else report.validation_accuracy
        evaluating = evaluate and run.cfg.loop.eval_episodes > 0
        if refit or not evaluating:
            with training.timed("writes"), self.db.write() as s:
                add_point(
                    s,
                    training.session_id,
                    round_index=training.round,
                    ppo_steps=run.agent.num_timesteps,
                    true_return=None,
                    pairs=len(run.dataset),
                    reward_val_accuracy=accuracy,
                    pool_steps=training.pool_steps,
                )
        if evaluate:
            training.evaluated_s = training.trained_s
        if evaluating:
            with training.timed("snapshots"):
                point = curve.snapshot(
                    training.session_id, training.round, run, accuracy, training.pool_steps
                )
            training.evaluating = self._evaluator_process().submit(point)

    def _evaluator_process(self) -> curve.Evaluator:
        if self._evaluator is None:
            self._evaluator = curve.Evaluator(self.db.url)
        return self._evaluator

    def _evaluation_due(self, training: LiveTraining) -> bool:
        """Whether to evaluate the policy again (`worker.curve`): the last evaluation has
        finished and the slices have trained long enough since."""
        if training.evaluating is not None:
            if not training.evaluating.done():
                return False
            try:
                training.eval_s = training.evaluating.result()
            except Exception:
                log.exception("session %s: evaluating the policy failed", training.session_id)
            training.evaluating = None
        since = training.trained_s - (training.evaluated_s or 0.0)
        return since >= max(curve.EVAL_MIN_S, curve.EVAL_COST * training.eval_s)

    def take(self, job: Job) -> LiveTraining:
        """The live training of `job`'s round, to end it (the training job): this worker's,
        or resumed from the live checkpoint and the database after a restart. A next round
        being published ahead is waited for: it opens as soon as it is ready."""
        training = self._live.pop(job.session_id, None)
        if training is not None and training.round == job.round:
            tick = time.perf_counter()
            _wait_staged(training)
            if (waited := time.perf_counter() - tick) > 0.1:
                log.info(
                    "session %s: waited %.1f s for round %d's clips",
                    job.session_id,
                    waited,
                    job.round + 1,
                )
            return training
        if training is not None:
            training.run.close()
        return self._resume(job)

    def close(self) -> None:
        for training in self._live.values():
            training.run.close()
        self._live.clear()
        self._staging.shutdown(wait=True, cancel_futures=True)
        if self._stager is not None:
            self._stager.close()
        if self._evaluator is not None:
            self._evaluator.close()

    def _training(self, job: Job) -> LiveTraining:
        training = self._live.get(job.session_id)
        if training is None or training.round != job.round:
            if training is not None:
                if training.round < job.round:  # its end opened the staged round at once
                    self._commit(job, training)
                training.run.close()
            training = self._live[job.session_id] = self._resume(job)
        return training

    def _commit(self, job: Job, training: LiveTraining) -> None:
        """Commit round `training.round`, ended by the person (or its budget or timer) while
        the round after it opened from its staged offer (`storage.staging`): `end_round` on
        the run that trained all along, then its record (module docstring)."""
        _wait_staged(training)
        with self.db.read() as s:
            pending = uncommitted_round(s, job.session_id)
            row = get_round(s, job.session_id, training.round)
            closed, shown_at = row.closed_at, row.shown_at
            shown = (closed - shown_at).total_seconds() if closed and shown_at else math.nan
        if pending != training.round:
            return  # committed already, or another round is (`_resume` sees to it)
        # the round's time shown, pauses included (its timer was reset when the next opened)
        ended = dataclasses.replace(job, round=pending, phase=TRAINING, elapsed_s=shown)
        record = commit_round(ended, self.db, self.data_dir, None, training)
        with self.db.write() as s:
            checkpoint = checkpoint_of(job.session_id, pending)
            record_training(s, job.session_id, pending, checkpoint, record.stats())
        log.info(
            "session %s: round %d committed (%d pairs, true return %.1f)",
            job.session_id,
            pending,
            record.pairs_total,
            record.true_return_mean,
        )

    def _resume(self, job: Job) -> LiveTraining:
        """The round as the last checkpoint (the round before, or this round's live one)
        left it, refitted on the round's judgements so far; a round before it that was not
        committed (`jobs.train` opened the next one first and the worker was killed) is
        committed first."""
        while True:
            with self.db.read() as s:
                pending = uncommitted_round(s, job.session_id)
            if pending is None:
                return self._resume_round(job)
            log.warning(
                "session %s: round %d was not committed; committing it", job.session_id, pending
            )
            # end_round may have written its checkpoint (and dropped the live one) before
            # the kill: then only the record is missing, and training again would lose PPO
            record = committed_record(self.data_dir, job.session_id, pending)
            if record is None:
                earlier = dataclasses.replace(
                    job, round=pending, phase=TRAINING, elapsed_s=math.nan
                )
                training = self._resume_round(earlier)
                with training.run:
                    record = commit_round(earlier, self.db, self.data_dir, None, training)
            with self.db.write() as s:
                checkpoint = checkpoint_of(job.session_id, pending)
                record_training(s, job.session_id, pending, checkpoint, record.stats())

    def _resume_round(self, job: Job) -> LiveTraining:
        run = open_run(job, self.data_dir, job.round - 1)
        resumed = run.restore_live(job.round)
        with self.db.read() as s:
            pool_dir = get_round(s, job.session_id, job.round).pool_dir
            keyed = round_judgements(s, job.session_id, job.round)
        if pool_dir is None:
            raise FileNotFoundError(f"round {job.round} has no pool directory")
        budget, mode = job.settings.comparisons_per_round, job.mode
        offer = published_offer(self.data_dir / pool_dir, job.round, budget, mode)
        streams = round_streams(run.cfg.loop.seed, job.round)
        now = time.monotonic()
        live = LiveRound(run, offer, streams, now)
        sampled = sampled_at(self.data_dir / pool_dir)
        pool_steps = curve.pool_steps(run) if sampled is None else sampled
        live.update(keyed, now, final=True)
        if run.cfg.loop.eval_episodes > 0:
            self._evaluator_process()  # started now: the round's first evaluation is near
        log.info(
            "session %s: round %d trains continuously%s",
            job.session_id,
            job.round,
            f" (resumed at {run.agent.num_timesteps:,} PPO steps)" if resumed else "",
        )
        return LiveTraining(job.session_id, job.round, run, live, now, now, pool_steps=pool_steps)

    def _continuous_sessions(self) -> tuple[list[Job], set[str]]:
        """The open rounds of continuous sessions, as jobs, and the sessions whose round
        just ended (training): one read of the sessions."""
        with self.db.read() as s:
            rows = sessions_in(s, (READY, TRAINING))
            settings = {row.id: settings_of(row) for row in rows}
            continuous = [
                row
                for row in rows
                if settings[row.id].training == CONTINUOUS
                and settings[row.id].driver == "app"
                and self.serves(row.id)
            ]
            jobs = [
                Job(
                    session_id=row.id,
                    env=row.env,
                    mode=row.mode,
                    phase=row.phase,
                    round=row.round,
                    settings=settings[row.id],
                    elapsed_s=0.0,
                )
                for row in continuous
                if row.phase == READY
            ]
            return jobs, {row.id for row in continuous if row.phase == TRAINING}


def _wait_staged(training: LiveTraining) -> None:
    """Wait for the next round being published ahead; a failure is logged (the round
    ending then prepares its next round as in rounds mode)."""
    if training.staged is None:
        return
    try:
        training.staged.result()
    except Exception:
        log.exception(
            "session %s: preparing round %d ahead failed", training.session_id, training.round + 1
        )
