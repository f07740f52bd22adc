"""The worker's third job: the final phase of a session (`groupwise.run.final`, docs/app.md).

finishing round r: when round r is one without feedback (the final phase after the last
    round, or "Continue training" with more steps): the checkpoint of round r − 1 →
    `run.round.train_frozen` (PPO for the round's steps on the frozen learned reward, the true
    return) → checkpoint ``round-r`` and ``rounds.csv``. Then, and also when the final phase
    has no steps (round r is the last feedback round), `run.final.publish_agent`: the greedy
    policy's video (``agent.mp4``), ``agent.zip`` and ``agent.json`` in the session's
    directory → phase ``finished``.

Re-running it after a crash repeats it exactly: it starts from round r − 1's checkpoint.
"""

import logging
from pathlib import Path

from groupwise.run.checkpoint import checkpoint_dir
from groupwise.run.final import publish_agent
from groupwise.run.round import train_frozen
from groupwise.storage import Database
from groupwise.storage.ending import frozen_rounds
from groupwise.storage.lifecycle import finish_final
from groupwise.storage.sessions import session_directory
from groupwise.worker.job import Job, open_run
from groupwise.worker.progress import JobProgress

log = logging.getLogger(__name__)


def finish(job: Job, db: Database, data_dir: Path, progress: JobProgress) -> None:
    """Run the final phase of the session's current round (module docstring)."""
    r, steps = job.round, job.frozen_steps
    progress.on_phase("load", 0, 1)
    with db.read() as s:
        frozen = frozen_rounds(s, job.session_id)
    checkpoint, stats = None, None
    with open_run(job, data_dir, r - 1 if steps is not None else r) as run:
        if steps is not None:
            record = train_frozen(run, steps, callback=progress)
            checkpoint = str(checkpoint_dir(Path(session_directory(job.session_id)), r))
            stats = record.stats()
        if job.settings.has_agent:  # a recorded dataset's session ends with its reward model
            publish_agent(run, frozen, frame_size=job.settings.frame_size, callback=progress)
    with db.write() as s:
        if not finish_final(s, job.session_id, r, checkpoint, stats):
            log.warning("session %s moved on while its final phase ran", job.session_id)
    log.info("session %s: final agent of round %d published", job.session_id, r)
