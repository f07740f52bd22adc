"""Session rows: ids and directories, creation, lookup and listing, and their round rows.

A session's phases are named in `groupwise.storage.phases` and changed by
`groupwise.storage.lifecycle`; its round timer is `groupwise.storage.timer`.

Every function takes an open `DbSession` and leaves committing to the caller (one
transaction per request, see `Database.write`). Functions that change a session bump its
`revision` (`touch`), which the event stream polls. Times are timezone-aware UTC.
"""

import secrets
from datetime import datetime
from pathlib import PurePosixPath

from sqlalchemy import select
from sqlalchemy.orm import Session as DbSession

from groupwise.storage.errors import NotFoundError, check_text
from groupwise.storage.models import RoundRow, SessionRow, utcnow
from groupwise.storage.phases import (
    FINISHED,
    PREPARING,
    READY,
    ROUND_PREPARING,
    WORK_PHASES,
)
from groupwise.storage.settings import LIBRARY, SessionSettings

MODES = ("groupwise", "pairwise")


def new_session_id() -> str:
    """A fresh session id, ``s-`` and 12 hex digits."""
    return f"s-{secrets.token_hex(6)}"


def round_directory(session_id: str, round_index: int) -> str:
    """Where round r's pool lives, relative to the data directory."""
    return str(PurePosixPath("sessions", session_id, f"round-{round_index:04d}"))


def session_directory(session_id: str) -> str:
    """The session's directory relative to the data directory (checkpoints live below it)."""
    return str(PurePosixPath("sessions", session_id))


def settings_of(session: SessionRow) -> SessionSettings:
    """The session's stored settings, parsed."""
    return SessionSettings.stored(session.settings)


def create_session(
    s: DbSession,
    env: str,
    mode: str,
    settings: SessionSettings,
    annotator: str = "",
    *,
    session_id: str | None = None,
    now: datetime | None = None,
) -> SessionRow:
    """Add a new session in phase ``preparing`` with round 0 waiting for its pool.

    Raises ValueError for an unknown mode (the caller validated env and settings),
    InvalidError for a NUL character in env or annotator (`check_text`).
    """
    if mode not in MODES:
        raise ValueError(f"mode must be one of {MODES}, got {mode!r}")
    check_text("env", env)
    check_text("annotator", annotator)
    now = now or utcnow()
    session = SessionRow(
        id=session_id or new_session_id(),
        env=env,
        mode=mode,
        settings=settings.model_dump(mode="json"),
        annotator=annotator,
        phase=PREPARING,
        round=0,
        progress_phase="queued",
        progress_fraction=0.0,
        progress_message="waiting for the training worker",
        revision=1,
        created_at=now,
        updated_at=now,
    )
    s.add(session)
    s.add(new_round(session.id, 0))
    s.flush()
    return session


def new_round(session_id: str, index: int) -> RoundRow:
    """Round `index` of a session, waiting for the worker to prepare its pool (not added)."""
    return RoundRow(
        session_id=session_id,
        index=index,
        phase=ROUND_PREPARING,
        pool_dir=round_directory(session_id, index),
    )


def get_session(s: DbSession, session_id: str, *, lock: bool = False) -> SessionRow:
    """The session `session_id`; `lock` takes its row lock (PostgreSQL) for an update.

    Raises NotFoundError.
    """
    query = select(SessionRow).where(SessionRow.id == session_id)
    if lock:
        query = query.with_for_update()
    session = s.scalars(query).one_or_none()
    if session is None:
        raise NotFoundError(f"there is no session {session_id!r}")
    return session


def get_round(s: DbSession, session_id: str, index: int) -> RoundRow:
    """Round `index` of a session. Raises NotFoundError."""
    row = s.scalars(
        select(RoundRow).where(RoundRow.session_id == session_id, RoundRow.index == index)
    ).one_or_none()
    if row is None:
        raise NotFoundError(f"session {session_id} has no round {index}")
    return row


def list_sessions(s: DbSession) -> list[SessionRow]:
    """Every session, newest first."""
    return list(s.scalars(select(SessionRow).order_by(SessionRow.created_at.desc())))


def find_resumable(
    s: DbSession, env: str, mode: str, dataset: str | None = None
) -> SessionRow | None:
    """The newest session of `env` and `mode` (and recorded `dataset`, None: none) that has
    not finished, if any."""
    query = (
        select(SessionRow)
        .where(SessionRow.env == env, SessionRow.mode == mode, SessionRow.phase != FINISHED)
        .order_by(SessionRow.created_at.desc())
    )
    rows = (row for row in s.scalars(query) if row.settings.get("dataset") == dataset)
    return next(rows, None)


def sessions_in(s: DbSession, phases: tuple[str, ...]) -> list[SessionRow]:
    """Sessions in any of `phases`, the longest-waiting first."""
    query = select(SessionRow).where(SessionRow.phase.in_(phases)).order_by(SessionRow.updated_at)
    return list(s.scalars(query))


def worker_sessions(s: DbSession) -> list[SessionRow]:
    """Sessions that wait for the app's training worker, the longest-waiting first (a
    session driven by a user's program through `WebTeacher` never does)."""
    return [row for row in sessions_in(s, WORK_PHASES) if row.settings.get("driver") != LIBRARY]


def training_open_rounds(s: DbSession) -> list[SessionRow]:
    """Open rounds the app's worker trains while the person compares (``training:
    "continuous"``), the longest-waiting first."""
    return [
        row
        for row in sessions_in(s, (READY,))
        if row.settings.get("driver") != LIBRARY and settings_of(row).training == "continuous"
    ]


def touch(session: SessionRow, now: datetime | None = None) -> None:
    """Record a change the page should hear of (bumps `revision`)."""
    session.revision += 1
    session.updated_at = now or utcnow()
