"""The open round's timer: shown time, pauses, and the round's time budget.

A round's timer starts when a page first shows it (`show_round`), so a round prepared while
nobody looked loses none of its budget; `pause` and `resume` stop and restart it. It counts
`timer_elapsed_s` (time run before the last start) plus the time since `timer_started_at`.
A round whose budget is used up is `round_due`; `groupwise.storage.lifecycle.close_if_due`
closes it.
"""

from datetime import datetime

from sqlalchemy import select
from sqlalchemy.orm import Session as DbSession

from groupwise.storage.errors import ConflictError
from groupwise.storage.models import RoundRow, SessionRow, utcnow
from groupwise.storage.phases import READY, require_ready
from groupwise.storage.sessions import get_round, get_session, touch


def elapsed(session: SessionRow, now: datetime | None = None) -> float:
    """Seconds the current round's timer has run (not counting pauses)."""
    running = 0.0
    if session.timer_started_at is not None:
        running = max(0.0, ((now or utcnow()) - session.timer_started_at).total_seconds())
    return session.timer_elapsed_s + running


def stop_timer(session: SessionRow, now: datetime) -> None:
    """Stop the timer, keeping the time it ran (no revision bump)."""
    session.timer_elapsed_s = elapsed(session, now)
    session.timer_started_at = None


def pause(s: DbSession, session_id: str, now: datetime | None = None) -> SessionRow:
    """Pause the open round's timer (idempotent). Raises ConflictError unless ready."""
    now = now or utcnow()
    session = get_session(s, session_id, lock=True)
    require_ready(session, "pause the timer")
    if not session.paused:
        stop_timer(session, now)
        session.paused = True
        touch(session, now)
    return session


def resume(s: DbSession, session_id: str, now: datetime | None = None) -> SessionRow:
    """Restart a paused timer (idempotent). Raises ConflictError unless ready."""
    now = now or utcnow()
    session = get_session(s, session_id, lock=True)
    require_ready(session, "resume the timer")
    if session.paused:
        session.paused = False
        session.timer_started_at = now
        touch(session, now)
    return session


def show_round(
    s: DbSession, session_id: str, round_index: int, now: datetime | None = None
) -> RoundRow:
    """A page shows the open round `round_index`: the first time, record the round's
    `shown_at` and start its timer (unless it is paused; `resume` starts it then).
    Idempotent. Raises NotFoundError, ConflictError (the round is not the open one)."""
    now = now or utcnow()
    session = get_session(s, session_id, lock=True)
    require_ready(session, f"show round {round_index}")
    if round_index != session.round:
        state = "closed" if round_index < session.round else "not open yet"
        raise ConflictError(f"round {round_index} is {state}; the open round is {session.round}")
    row = get_round(s, session_id, round_index)
    if row.shown_at is None:
        row.shown_at = now
        if not session.paused and session.timer_started_at is None:
            session.timer_started_at = now
        touch(session, now)
    return row


def shown_at(s: DbSession, session: SessionRow) -> datetime | None:
    """When a page first showed the session's current round (None: not yet, or no round)."""
    return s.scalars(
        select(RoundRow.shown_at).where(
            RoundRow.session_id == session.id, RoundRow.index == session.round
        )
    ).one_or_none()


def remaining(session: SessionRow, now: datetime | None = None) -> float | None:
    """Seconds left of the open round's time budget while its timer runs; None when the
    round has no budget or its timer is not running (paused, or no page showed it yet):
    then it ends by no clock."""
    budget = float(session.settings.get("round_seconds", 0))
    if session.phase != READY or budget <= 0 or session.timer_started_at is None:
        return None
    return budget - elapsed(session, now)


def round_due(session: SessionRow, now: datetime | None = None) -> bool:
    """Whether the open round's time budget is used up (never with a budget of 0)."""
    if session.phase != READY:
        return False
    budget = float(session.settings.get("round_seconds", 0))
    return budget > 0 and elapsed(session, now) >= budget
