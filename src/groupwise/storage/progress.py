"""A session's progress line: what the worker is doing, how far along, in words.

The page shows it under the session's phase; every phase change in
`groupwise.storage.lifecycle` rewrites it, and the worker reports through `set_progress`.
"""

from datetime import datetime

from sqlalchemy.orm import Session as DbSession

from groupwise.storage.models import SessionRow
from groupwise.storage.sessions import get_session, touch


def write_progress(session: SessionRow, phase: str, fraction: float, message: str) -> None:
    """Set the session row's progress (`fraction` clipped to [0, 1]); no revision bump."""
    session.progress_phase = phase
    session.progress_fraction = float(min(1.0, max(0.0, fraction)))
    session.progress_message = message


def set_progress(
    s: DbSession,
    session_id: str,
    expected_phase: str,
    phase: str,
    fraction: float,
    message: str,
    now: datetime | None = None,
) -> bool:
    """Write the worker's progress; False (and nothing written) when the session is no
    longer in `expected_phase` (e.g. marked failed by the supervisor meanwhile)."""
    session = get_session(s, session_id, lock=True)
    if session.phase != expected_phase:
        return False
    write_progress(session, phase, fraction, message)
    touch(session, now)
    return True
