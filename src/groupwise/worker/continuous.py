"""Continuous training in the app (issues 24, 39): the worker trains an open round's policy
while the person compares, instead of idling until the round ends.

Whenever no phase job waits (`process.Worker`), `ContinuousSessions.step` gives one open session
with ``training: "continuous"`` one slice (`continuous_round.train_slice`: the judgements read,
the reward refitted when due, one PPO rollout), the sessions taking turns. A session whose
timer is paused trains no PPO until it is resumed, so "Pause" pauses the agent too.

A round's next pool is cut a few comparisons before its budget ends it, or a few seconds
before its timer does (`continuous_round.stage_due`), and PPO waits for that end. The
round's end (the person, its budget or its timer) queues its training job and stops the
slice in progress (`continuous_round.round_ended`); the job takes
the round's run from here (`take`): the next round's pool is cut from that run's latest
rollouts and opened, then the round is committed (`jobs.train`, `jobs.open_fresh`), and the
same run trains on into the next round (`keep`), its recorded rollouts kept. A round this
worker does not hold (a restarted worker) is resumed from its mid-round checkpoint
(`worker.resume`).
"""

import dataclasses
import logging
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from groupwise.storage import Database
from groupwise.storage.phases import READY, TRAINING
from groupwise.storage.sessions import sessions_in, settings_of
from groupwise.worker import curve
from groupwise.worker.continuous_round import ContinuousTraining, train_slice
from groupwise.worker.job import Job
from groupwise.worker.resume import resume, resume_round

if TYPE_CHECKING:
    from groupwise.clips.render import RenderPool
    from groupwise.worker.jobs import CutRound

log = logging.getLogger(__name__)

CONTINUOUS = "continuous"


class ContinuousSessions:
    """The worker's continuous rounds, one `ContinuousTraining` per open session (module
    docstring)."""

    def __init__(
        self,
        db: Database,
        data_dir: Path,
        serves: Callable[[str], bool] = lambda _: True,
        render: "Callable[[int], RenderPool] | None" = None,
    ) -> None:
        self.db = db
        self.data_dir = data_dir
        self.serves = serves
        """Whether this worker serves a session (`process.Worker.serves`)."""
        self.render = render
        """The worker's render pool of a number of workers, to cut a round's next pool
        before its budget ends it (`continuous_round.stage_due`); None: cut at its end."""
        self._rounds: dict[str, ContinuousTraining] = {}
        self._turns: dict[str, int] = {}
        self._turn = 0
        self._evaluator: curve.Evaluator | None = None
        self._broken: dict[str, int] = {}
        """Sessions whose continuous training failed, and the round: left alone until the
        round ends (its training job then tries once more and fails visibly if it must)."""

    def step(self) -> bool:
        """One slice of training for the open continuous session whose turn it is (a session
        with nothing to learn from yet, or paused, passes its turn on); False when none
        trained (the worker then sleeps)."""
        open_jobs, held = self._continuous_sessions()
        jobs = [job for job in open_jobs if self._broken.get(job.session_id) != job.round]
        # a paused or just ended round keeps its run (for its resumption or training job)
        for stale in set(self._rounds) - {job.session_id for job in jobs} - held:
            self._rounds.pop(stale).run.close()
        for job in sorted(jobs, key=lambda j: self._turns.get(j.session_id, -1)):
            self._turn += 1
            self._turns[job.session_id] = self._turn
            try:
                training = self._training(job)
                tick = time.perf_counter()
                trained = train_slice(training, self.db, self.evaluator, *self._stager(job))
            except Exception:
                log.exception(
                    "session %s: continuous training of round %d failed",
                    job.session_id,
                    job.round,
                )
                self._broken[job.session_id] = job.round
                if (broken := self._rounds.pop(job.session_id, None)) is not None:
                    broken.run.close()
                return True
            training.longest_slice_s = max(training.longest_slice_s, time.perf_counter() - tick)
            if trained:
                return True
        return False

    def take(self, job: Job) -> ContinuousTraining:
        """The continuous training of `job`'s round, to end it (the training job): this worker's,
        or resumed from the mid-round checkpoint and the database after a restart."""
        training = self._rounds.pop(job.session_id, None)
        if training is not None and training.round == job.round:
            return training
        if training is not None:
            training.run.close()
        return resume(job, self.db, self.data_dir, self.evaluator)

    def keep(self, job: Job, training: ContinuousTraining, opened: bool) -> None:
        """After `job`'s training job: with the next round `opened`, train on into it on the
        same run (its recorded rollouts and statistics kept: no reload from the checkpoint
        just written); else close the run."""
        if not opened:
            training.run.close()
            return
        following = dataclasses.replace(job, round=job.round + 1, phase=READY, elapsed_s=0.0)
        try:
            self._rounds[job.session_id] = resume_round(
                following, self.db, self.data_dir, self.evaluator, run=training.run
            )
            self._rounds[job.session_id].cut_s = training.cut_s  # how early to cut next
        except Exception:
            training.run.close()
            raise

    def _stager(self, job: Job) -> "tuple[Callable[[ContinuousTraining], CutRound] | None, int]":
        """How `train_slice` cuts `job`'s next round before its budget or its timer ends it,
        and the round's budget (none for the session's last round, or without a render
        pool)."""
        settings, render = job.settings, self.render
        if render is None or job.round + 1 >= settings.rounds:
            return None, 0

        def stage(training: ContinuousTraining) -> "CutRound":
            from groupwise.worker.jobs import cut_fresh

            pool = render(settings.render_workers)
            return cut_fresh(job, self.data_dir, training.continuous, pool)

        return stage, settings.comparisons_per_round

    def evaluator(self) -> curve.Evaluator:
        """The process that evaluates the curve's points, started on first use."""
        if self._evaluator is None:
            self._evaluator = curve.Evaluator(self.db.url)
        return self._evaluator

    def close(self) -> None:
        for training in self._rounds.values():
            training.run.close()
        self._rounds.clear()
        if self._evaluator is not None:
            self._evaluator.close()

    def _training(self, job: Job) -> ContinuousTraining:
        training = self._rounds.get(job.session_id)
        if training is None or training.round != job.round:
            if training is not None:
                training.run.close()
            training = self._rounds[job.session_id] = resume(
                job, self.db, self.data_dir, self.evaluator
            )
        return training

    def _continuous_sessions(self) -> tuple[list[Job], set[str]]:
        """The open, unpaused rounds of continuous sessions, as jobs, and the sessions whose
        run is kept meanwhile (paused, or their round just ended): one read of the sessions."""
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
                if row.phase == READY and not row.paused
            ]
            held = {row.id for row in continuous if row.phase == TRAINING or row.paused}
            return jobs, held
