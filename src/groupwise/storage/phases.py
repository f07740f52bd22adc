"""The phases of a session and of its rounds, and the guard for actions on the open round.

A session (docs/app.md): ``preparing`` (the worker builds round r's pool) → ``ready`` (round r
is open) → ``training`` (round r closed; reward model and PPO train) → ``preparing`` (r + 1)
… → ``finishing`` (the final phase: PPO on the frozen learned reward in a round without
feedback, then the agent's video and download) → ``finished``; ``failed`` when a worker step
raised or the worker died, with `failed_phase` naming the step that `retry` re-queues.
`groupwise.storage.lifecycle` makes these moves; "Finish now" and "Continue training"
(`groupwise.storage.ending`) make some too.

A round: ``preparing`` (its pool is being built) → ``open`` → ``closed``.
"""

from groupwise.storage.errors import ConflictError
from groupwise.storage.models import SessionRow

PREPARING = "preparing"
READY = "ready"
TRAINING = "training"
FINISHING = "finishing"
FINISHED = "finished"
FAILED = "failed"
PHASES = (PREPARING, READY, TRAINING, FINISHING, FINISHED, FAILED)
WORK_PHASES = (PREPARING, TRAINING, FINISHING)
"""Phases in which the worker has a job to do for the session."""

ROUND_PREPARING = "preparing"
ROUND_OPEN = "open"
ROUND_CLOSED = "closed"


def require_ready(session: SessionRow, action: str) -> None:
    """Raises ConflictError naming `action` unless the session's round is open."""
    if session.phase != READY:
        raise ConflictError(f"cannot {action}: session {session.id} is {session.phase}")
