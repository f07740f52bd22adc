"""A session's phase changes, in the order a session goes through them (the phases:
`groupwise.storage.phases`): the worker opens a prepared round, a person, the comparison
budget or the timer closes it, the worker's training queues the next round or the final
phase, the final phase finishes the session; a failed worker step is marked and retried.

Every function takes an open `DbSession`, leaves committing to the caller, and bumps the
session's `revision` when it changes the session.
"""

from datetime import datetime

from sqlalchemy import select
from sqlalchemy.orm import Session as DbSession

from groupwise.storage.errors import ConflictError
from groupwise.storage.models import CheckpointRow, RoundRow, SessionRow, utcnow
from groupwise.storage.phases import (
    FAILED,
    FINISHED,
    FINISHING,
    PREPARING,
    READY,
    ROUND_CLOSED,
    ROUND_OPEN,
    TRAINING,
    WORK_PHASES,
    require_ready,
)
from groupwise.storage.progress import write_progress
from groupwise.storage.sessions import get_round, get_session, new_round, settings_of, touch
from groupwise.storage.settings import LIBRARY
from groupwise.storage.timer import round_due, stop_timer
from groupwise.storage.training import round_point


def open_round(s: DbSession, session: SessionRow, now: datetime | None = None) -> RoundRow:
    """The worker prepared the current round: open it, phase ``ready``. Its timer starts
    when a page first shows it (`show_round`), so a round nobody looks at uses no time."""
    now = now or utcnow()
    row = get_round(s, session.id, session.round)
    row.phase = ROUND_OPEN
    row.opened_at = now
    row.shown_at = None
    session.phase = READY
    session.failed_phase = None
    session.error = None
    session.timer_elapsed_s = 0.0
    session.timer_started_at = None
    session.paused = False
    write_progress(session, "ready", 1.0, f"round {session.round} is open")
    touch(session, now)
    return row


def close_round(
    s: DbSession,
    session: SessionRow,
    reason: str,
    now: datetime | None = None,
) -> RoundRow:
    """End the open round (`reason`: "user", "comparisons" or "time"): phase ``training``,
    for the worker to train (rounds) or to open the next round from the latest rollouts and
    commit this one (continuous, `worker.jobs.open_fresh`).

    Raises ConflictError unless the session is ready.
    """
    now = now or utcnow()
    require_ready(session, "end the round")
    row = get_round(s, session.id, session.round)
    row.phase = ROUND_CLOSED
    row.closed_at = now
    row.close_reason = reason
    stop_timer(session, now)
    session.phase = TRAINING
    write_progress(session, "queued", 0.0, "waiting for the training worker")
    touch(session, now)
    return row


def close_open_round(s: DbSession, session_id: str, now: datetime | None = None) -> SessionRow:
    """The user ends the open round. Raises NotFoundError, ConflictError."""
    session = get_session(s, session_id, lock=True)
    close_round(s, session, "user", now)
    return session


def close_if_due(s: DbSession, session_id: str, now: datetime | None = None) -> bool:
    """Close the open round when its time is up (checked lazily on reads); True if closed."""
    now = now or utcnow()
    session = get_session(s, session_id, lock=True)
    if not round_due(session, now):
        return False
    close_round(s, session, "time", now)
    return True


def finish_training(
    s: DbSession,
    session_id: str,
    round_index: int,
    checkpoint: str,
    stats: dict[str, object],
    now: datetime | None = None,
) -> bool:
    """The worker trained after round `round_index` and wrote `checkpoint` (a directory
    relative to the data directory): queue the next round or finish. False (nothing
    written) when the session is no longer training that round."""
    now = now or utcnow()
    session = get_session(s, session_id, lock=True)
    if session.phase != TRAINING or session.round != round_index:
        return False
    record_training(s, session_id, round_index, checkpoint, stats, now)
    _advance(s, session, now)
    return True


def advance_before_commit(s: DbSession, session_id: str, round_index: int) -> bool:
    """Queue round `round_index + 1` before round `round_index`'s training is recorded
    (continuous training opens the next round first: the person compares again while the
    worker commits the round, `record_training`). False (nothing written) when
    the session is no longer training that round or it was the last round."""
    session = get_session(s, session_id, lock=True)
    if session.phase != TRAINING or session.round != round_index:
        return False
    if round_index + 1 >= int(session.settings.get("rounds", 1)):
        return False
    _advance(s, session, utcnow())
    return True


def record_training(
    s: DbSession,
    session_id: str,
    round_index: int,
    checkpoint: str,
    stats: dict[str, object],
    now: datetime | None = None,
) -> None:
    """Store what the training after round `round_index` reported and the checkpoint it
    wrote (a directory relative to the data directory)."""
    now = now or utcnow()
    row = get_round(s, session_id, round_index)
    row.stats = dict(stats)
    s.add(CheckpointRow(round_id=row.id, path=checkpoint, created_at=now))
    round_point(s, session_id, round_index, row.stats, now)


def uncommitted_round(s: DbSession, session_id: str) -> int | None:
    """A feedback round before the current one whose training is not recorded yet
    (`advance_before_commit` and the worker stopped before `record_training`), or None."""
    session = get_session(s, session_id)
    rows = s.scalars(
        select(RoundRow)
        .where(
            RoundRow.session_id == session_id,
            RoundRow.index < session.round,
            RoundRow.phase == ROUND_CLOSED,
            RoundRow.frozen_steps.is_(None),
            RoundRow.pool_dir.is_not(None),
        )
        .order_by(RoundRow.index)
    )
    # stats in Python: a JSON column may hold JSON null rather than SQL NULL
    return next((row.index for row in rows if row.stats is None), None)


def _advance(s: DbSession, session: SessionRow, now: datetime) -> None:
    """The round's training is done (or, continuous, under way): queue the next round, or
    finish."""
    rounds = int(session.settings.get("rounds", 1))
    if session.round + 1 < rounds:
        session.round += 1
        session.phase = PREPARING
        s.add(new_round(session.id, session.round))
        write_progress(session, "queued", 0.0, f"round {session.round}: waiting for the worker")
    elif session.settings.get("driver") == LIBRARY:  # the program trains its agent itself
        session.phase = FINISHED
        write_progress(session, "finished", 1.0, "all rounds are done")
    else:
        start_final(s, session, settings_of(session).final_ppo_steps, "final", now)
    session.failed_phase = None
    session.error = None
    touch(session, now)


def start_final(
    s: DbSession, session: SessionRow, steps: int, reason: str, now: datetime | None = None
) -> None:
    """Queue the final phase after the session's current round: a round without feedback
    (the next index) training PPO for `steps` on the frozen learned reward, then the
    agent's video and download; with `steps` = 0 no such round, the current round's agent
    is published as it is. Phase ``finishing``; `reason` is the round's close reason."""
    now = now or utcnow()
    if steps > 0:
        session.round += 1
        s.add(
            RoundRow(
                session_id=session.id,
                index=session.round,
                phase=ROUND_CLOSED,
                pool_dir=None,
                closed_at=now,
                close_reason=reason,
                frozen_steps=steps,
            )
        )
    session.phase = FINISHING
    write_progress(session, "queued", 0.0, "final training: waiting for the worker")
    touch(session, now)


def finish_final(
    s: DbSession,
    session_id: str,
    round_index: int,
    checkpoint: str | None,
    stats: dict[str, object] | None,
    now: datetime | None = None,
) -> bool:
    """The worker ran the final phase of round `round_index` (its checkpoint, a directory
    relative to the data directory, and record when it trained one) and published the
    agent: phase ``finished``. False (nothing written) when the session moved on."""
    now = now or utcnow()
    session = get_session(s, session_id, lock=True)
    if session.phase != FINISHING or session.round != round_index:
        return False
    if checkpoint is not None:
        row = get_round(s, session.id, round_index)
        row.stats = dict(stats or {})
        s.add(CheckpointRow(round_id=row.id, path=checkpoint, created_at=now))
        round_point(s, session.id, round_index, row.stats, now)
    session.phase = FINISHED
    session.failed_phase = None
    session.error = None
    write_progress(session, "finished", 1.0, "the final agent is ready")
    touch(session, now)
    return True


def finish_session(s: DbSession, session_id: str, now: datetime | None = None) -> SessionRow:
    """The program driving a library session is done with it: phase ``finished``."""
    session = get_session(s, session_id, lock=True)
    session.phase = FINISHED
    stop_timer(session, now or utcnow())
    write_progress(session, "finished", 1.0, "the program's rounds are done")
    touch(session, now)
    return session


def mark_failed(
    s: DbSession, session_id: str, phase: str, error: str, now: datetime | None = None
) -> SessionRow | None:
    """Record that the worker's `phase` step failed; None when the session moved on since."""
    session = get_session(s, session_id, lock=True)
    if session.phase != phase:
        return None
    session.phase = FAILED
    session.failed_phase = phase
    session.error = error
    touch(session, now)
    return session


def retry(s: DbSession, session_id: str, now: datetime | None = None) -> SessionRow:
    """Re-queue the failed step. Raises ConflictError unless the session failed."""
    session = get_session(s, session_id, lock=True)
    if session.phase != FAILED or session.failed_phase not in WORK_PHASES:
        raise ConflictError(f"session {session_id} has not failed; it is {session.phase}")
    session.phase = session.failed_phase
    session.failed_phase = None
    session.error = None
    write_progress(session, "queued", 0.0, "retrying: waiting for the training worker")
    touch(session, now)
    return session
