"""A continuous round taken up by a worker: the run as the last checkpoint left it, refitted
on the round's judgements so far.

The database holds every acknowledged judgement, so a killed worker loses none: the next one
resumes the round from its mid-round checkpoint (or the round before's) and refits on all of
them. A round before it that was not committed (the training job opened the next round
first, `jobs.open_fresh`, and the worker was killed) is committed first: from its checkpoint
when `end_round` wrote one before the kill, else on a run resumed for it.
"""

import dataclasses
import logging
import math
import time
from collections.abc import Callable
from pathlib import Path

from groupwise.run.continuous import ContinuousRound
from groupwise.run.run import Run
from groupwise.run.streams import round_streams
from groupwise.storage import Database
from groupwise.storage.judgements import round_judgements
from groupwise.storage.lifecycle import record_training, uncommitted_round
from groupwise.storage.phases import TRAINING
from groupwise.storage.sessions import get_round
from groupwise.worker import curve
from groupwise.worker.continuous_round import ContinuousTraining
from groupwise.worker.job import Job, checkpoint_of, committed_record, open_run
from groupwise.worker.jobs import commit_round, pool_steps_of
from groupwise.worker.publishing import published_offer, sampled_at

log = logging.getLogger(__name__)


def resume(
    job: Job, db: Database, data_dir: Path, evaluator: Callable[[], curve.Evaluator]
) -> ContinuousTraining:
    """`job`'s round as the last checkpoint left it, any round before it committed first
    (module docstring); `evaluator` is started when the round will evaluate."""
    while True:
        with db.read() as s:
            pending = uncommitted_round(s, job.session_id)
        if pending is None:
            return resume_round(job, db, data_dir, evaluator)
        log.warning(
            "session %s: round %d was not committed; committing it", job.session_id, pending
        )
        # end_round may have written its checkpoint (and dropped the mid-round one) before
        # the kill: then only the record is missing, and training again would lose PPO
        record = committed_record(data_dir, job.session_id, pending)
        if record is None:
            earlier = dataclasses.replace(job, round=pending, phase=TRAINING, elapsed_s=math.nan)
            training = resume_round(earlier, db, data_dir, evaluator)
            with training.run:
                record = commit_round(earlier, db, data_dir, None, training.continuous)
        stats = {
            **record.stats(),
            "pool_steps": pool_steps_of(db, data_dir, job.session_id, pending),
        }
        with db.write() as s:
            checkpoint = checkpoint_of(job.session_id, pending)
            record_training(s, job.session_id, pending, checkpoint, stats)


def resume_round(
    job: Job,
    db: Database,
    data_dir: Path,
    evaluator: Callable[[], curve.Evaluator],
    run: Run | None = None,
) -> ContinuousTraining:
    """Round `job.round` on the session's run from its mid-round checkpoint (or the round
    before's), refitted on its judgements so far; on `run` instead when the worker holds it
    (as the round before left it, committed)."""
    resumed = False
    if run is None:
        run = open_run(job, data_dir, job.round - 1)
        resumed = run.restore_mid_round(job.round)
    with db.read() as s:
        pool_dir = get_round(s, job.session_id, job.round).pool_dir
        keyed = round_judgements(s, job.session_id, job.round)
    if pool_dir is None:
        raise FileNotFoundError(f"round {job.round} has no pool directory")
    budget, mode = job.settings.comparisons_per_round, job.mode
    offer = published_offer(data_dir / pool_dir, job.round, budget, mode)
    streams = round_streams(run.cfg.loop.seed, job.round)
    now = time.monotonic()
    continuous = ContinuousRound(run, offer, streams, now)
    sampled = sampled_at(data_dir / pool_dir)
    pool_steps = curve.pool_steps(run) if sampled is None else sampled
    continuous.update(keyed, now, final=True)
    if run.cfg.loop.eval_episodes > 0:
        evaluator()  # started now: the round's first evaluation is near
    log.info(
        "session %s: round %d trains continuously%s",
        job.session_id,
        job.round,
        f" (resumed at {run.agent.num_timesteps:,} PPO steps)" if resumed else "",
    )
    return ContinuousTraining(
        job.session_id, job.round, run, continuous, now, pool_steps=pool_steps
    )
