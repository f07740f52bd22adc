"""The worker's third job: the final phase of a session (`groupwise.final`, docs/app.md).

finishing round r: when round r is one without feedback (the final phase after the last
    round, or "Continue training" with more steps): the checkpoint of round r − 1 →
    `loop.train_frozen` (PPO for the round's steps on the frozen learned reward, the true
    return) → checkpoint ``round-r`` and ``rounds.csv``. Then, and also when the final phase
    has no steps (round r is the last feedback round), `final.publish_agent`: the greedy
    policy's video (``agent.mp4``), ``agent.zip`` and ``agent.json`` in the session's
    directory → phase ``finished``.

Re-running it after a crash repeats it exactly: it starts from round r − 1's checkpoint.
"""

import logging
from pathlib import Path

from groupwise.checkpoint import checkpoint_dir
from groupwise.final import publish_agent
from groupwise.loop import RESULTS_FILE, train_frozen, write_records
from groupwise.server.jobs import Job, load_session, record_stats
from groupwise.server.progress import ProgressReporter
from groupwise.storage import Database
from groupwise.storage.ending import frozen_rounds
from groupwise.storage.sessions import finish_final, session_directory

log = logging.getLogger(__name__)

_PHASES = {
    # phase: (fraction at its start, share of the bar it fills)
    "ppo": (0.05, 0.8),
    "eval": (0.86, 0.0),
    "video": (0.9, 0.0),
    "package": (0.96, 0.0),
}


def _message(phase: str, done: int, total: int) -> str:
    return {
        "ppo": f"PPO on the frozen reward model {done:,} / {total:,} steps",
        "eval": "measuring the agent's true return",
        "video": "filming the final agent",
        "package": "packing the agent for download",
    }[phase]


def finish(job: Job, db: Database, data_dir: Path, progress: ProgressReporter) -> None:
    """Run the final phase of the session's current round (module docstring)."""
    r, steps = job.round, job.frozen_steps
    progress.report("load", 0.02, "loading the policy and reward model", force=True)
    _, session, out = load_session(job, data_dir, r - 1 if steps is not None else r)

    def report(phase: str, done: int, total: int) -> None:
        start, share = _PHASES[phase]
        fraction = start + share * done / max(total, 1)
        progress.report(phase, fraction, _message(phase, done, total), force=phase != "ppo")

    with db.read() as s:
        frozen = frozen_rounds(s, job.session_id)
    checkpoint, stats = None, None
    try:
        if steps is not None:
            record = train_frozen(session, r, steps, report=report)
            progress.report("checkpoint", 0.88, "saving the checkpoint", force=True)
            session.save(out)
            write_records(out / RESULTS_FILE, session.records)
            checkpoint = str(checkpoint_dir(Path(session_directory(job.session_id)), r))
            stats = record_stats(record)
        publish_agent(session, out, frozen, frame_size=job.settings.frame_size, report=report)
    finally:
        session.ppo.close()
    with db.write() as s:
        if not finish_final(s, job.session_id, r, checkpoint, stats):
            log.warning("session %s moved on while its final phase ran", job.session_id)
    log.info("session %s: final agent of round %d published", job.session_id, r)
