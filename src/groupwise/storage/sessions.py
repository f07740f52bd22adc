"""Sessions and their lifecycle: phases, the round timer, progress, counts.

Phases (docs/app.md): ``preparing`` (the worker builds round r's pool) → ``ready`` (round r
is open) → ``training`` (round r closed; reward model and PPO train) → ``preparing`` (r + 1)
… → ``finishing`` (the final phase: PPO on the frozen learned reward in a round without
feedback, then the agent's video and download) → ``finished``; ``failed`` when a worker step
raised or the worker died, with `failed_phase` naming the step that `retry` re-queues.
"Finish now" and "Continue training" (`groupwise.storage.ending`) move a session between
these phases too.

Every function takes an open ORM `Session` and leaves committing to the caller (one
transaction per request, see `Database.write`). Functions that change a session bump its
`revision`, which the event stream polls. Times are timezone-aware UTC.
"""

import secrets
from dataclasses import dataclass
from datetime import datetime
from pathlib import PurePosixPath

from sqlalchemy import func, select
from sqlalchemy.orm import Session

from groupwise.storage.errors import ConflictError, NotFoundError
from groupwise.storage.models import (
    CheckpointRow,
    JudgementRow,
    PairRow,
    RoundRow,
    SessionRow,
    utcnow,
)
from groupwise.storage.settings import LIBRARY, SessionSettings

PREPARING = "preparing"
READY = "ready"
TRAINING = "training"
FINISHING = "finishing"
FINISHED = "finished"
FAILED = "failed"
PHASES = (PREPARING, READY, TRAINING, FINISHING, FINISHED, FAILED)
WORK_PHASES = (PREPARING, TRAINING, FINISHING)
"""Phases in which the worker has a job to do for the session."""
MODES = ("groupwise", "pairwise")

ROUND_PREPARING = "preparing"
ROUND_OPEN = "open"
ROUND_CLOSED = "closed"


@dataclass(frozen=True)
class Counts:
    """Non-undone judgements and their pairs, in the current round and in total."""

    comparisons_round: int
    pairs_round: int
    comparisons_total: int
    pairs_total: int


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
    return SessionSettings.model_validate(session.settings)


def create_session(
    s: Session,
    env: str,
    mode: str,
    settings: SessionSettings,
    annotator: str = "",
    *,
    session_id: str | None = None,
    now: datetime | None = None,
) -> SessionRow:
    """Add a new session in phase ``preparing`` with round 0 waiting for its pool.

    Raises ValueError for an unknown mode (the caller validated env and settings).
    """
    if mode not in MODES:
        raise ValueError(f"mode must be one of {MODES}, got {mode!r}")
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
    s.add(_new_round(session.id, 0))
    s.flush()
    return session


def _new_round(session_id: str, index: int) -> RoundRow:
    return RoundRow(
        session_id=session_id,
        index=index,
        phase=ROUND_PREPARING,
        pool_dir=round_directory(session_id, index),
    )


def get_session(s: Session, session_id: str, *, lock: bool = False) -> SessionRow:
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


def list_sessions(s: Session) -> list[SessionRow]:
    """Every session, newest first."""
    return list(s.scalars(select(SessionRow).order_by(SessionRow.created_at.desc())))


def find_resumable(s: Session, env: str, mode: str) -> SessionRow | None:
    """The newest session of `env` and `mode` that has not finished, if any."""
    query = (
        select(SessionRow)
        .where(SessionRow.env == env, SessionRow.mode == mode, SessionRow.phase != FINISHED)
        .order_by(SessionRow.created_at.desc())
        .limit(1)
    )
    return s.scalars(query).one_or_none()


def sessions_in(s: Session, phases: tuple[str, ...]) -> list[SessionRow]:
    """Sessions in any of `phases`, the longest-waiting first."""
    query = select(SessionRow).where(SessionRow.phase.in_(phases)).order_by(SessionRow.updated_at)
    return list(s.scalars(query))


def worker_sessions(s: Session) -> list[SessionRow]:
    """Sessions that wait for the app's training worker, the longest-waiting first (a
    session driven by a user's program through `WebTeacher` never does)."""
    return [row for row in sessions_in(s, WORK_PHASES) if row.settings.get("driver") != LIBRARY]


def finish_session(s: Session, session_id: str, now: datetime | None = None) -> SessionRow:
    """The program driving a library session is done with it: phase ``finished``."""
    session = get_session(s, session_id, lock=True)
    session.phase = FINISHED
    _stop_timer(session, now or utcnow())
    _set_progress(session, "finished", 1.0, "the program's rounds are done")
    touch(session, now)
    return session


def get_round(s: Session, session_id: str, index: int) -> RoundRow:
    """Round `index` of a session. Raises NotFoundError."""
    row = s.scalars(
        select(RoundRow).where(RoundRow.session_id == session_id, RoundRow.index == index)
    ).one_or_none()
    if row is None:
        raise NotFoundError(f"session {session_id} has no round {index}")
    return row


def touch(session: SessionRow, now: datetime | None = None) -> None:
    """Record a change the page should hear of (bumps `revision`)."""
    session.revision += 1
    session.updated_at = now or utcnow()


# ------------------------------------------------------------------ the round timer


def elapsed(session: SessionRow, now: datetime | None = None) -> float:
    """Seconds the current round's timer has run (not counting pauses)."""
    running = 0.0
    if session.timer_started_at is not None:
        running = max(0.0, ((now or utcnow()) - session.timer_started_at).total_seconds())
    return session.timer_elapsed_s + running


def _stop_timer(session: SessionRow, now: datetime) -> None:
    session.timer_elapsed_s = elapsed(session, now)
    session.timer_started_at = None


def pause(s: Session, session_id: str, now: datetime | None = None) -> SessionRow:
    """Pause the open round's timer (idempotent). Raises ConflictError unless ready."""
    now = now or utcnow()
    session = get_session(s, session_id, lock=True)
    _require_ready(session, "pause the timer")
    if not session.paused:
        _stop_timer(session, now)
        session.paused = True
        touch(session, now)
    return session


def resume(s: Session, session_id: str, now: datetime | None = None) -> SessionRow:
    """Restart a paused timer (idempotent). Raises ConflictError unless ready."""
    now = now or utcnow()
    session = get_session(s, session_id, lock=True)
    _require_ready(session, "resume the timer")
    if session.paused:
        session.paused = False
        session.timer_started_at = now
        touch(session, now)
    return session


def show_round(
    s: Session, session_id: str, round_index: int, now: datetime | None = None
) -> RoundRow:
    """A page shows the open round `round_index`: the first time, record the round's
    `shown_at` and start its timer (unless it is paused; `resume` starts it then).
    Idempotent. Raises NotFoundError, ConflictError (the round is not the open one)."""
    now = now or utcnow()
    session = get_session(s, session_id, lock=True)
    _require_ready(session, f"show round {round_index}")
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


def shown_at(s: Session, session: SessionRow) -> datetime | None:
    """When a page first showed the session's current round (None: not yet, or no round)."""
    return s.scalars(
        select(RoundRow.shown_at).where(
            RoundRow.session_id == session.id, RoundRow.index == session.round
        )
    ).one_or_none()


def round_due(session: SessionRow, now: datetime | None = None) -> bool:
    """Whether the open round's time budget is used up (never with a budget of 0)."""
    if session.phase != READY:
        return False
    budget = float(session.settings.get("round_seconds", 0))
    return budget > 0 and elapsed(session, now) >= budget


# ------------------------------------------------------------------ phase changes


def _require_ready(session: SessionRow, action: str) -> None:
    if session.phase != READY:
        raise ConflictError(f"cannot {action}: session {session.id} is {session.phase}")


def open_round(s: Session, session: SessionRow, now: datetime | None = None) -> RoundRow:
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
    _set_progress(session, "ready", 1.0, f"round {session.round} is open")
    touch(session, now)
    return row


def close_round(
    s: Session, session: SessionRow, reason: str, now: datetime | None = None
) -> RoundRow:
    """End the open round (`reason`: "user", "comparisons" or "time"); phase ``training``.

    Raises ConflictError unless the session is ready.
    """
    now = now or utcnow()
    _require_ready(session, "end the round")
    row = get_round(s, session.id, session.round)
    row.phase = ROUND_CLOSED
    row.closed_at = now
    row.close_reason = reason
    _stop_timer(session, now)
    session.phase = TRAINING
    _set_progress(session, "queued", 0.0, "waiting for the training worker")
    touch(session, now)
    return row


def end_round(s: Session, session_id: str, now: datetime | None = None) -> SessionRow:
    """The user ends the open round. Raises NotFoundError, ConflictError."""
    session = get_session(s, session_id, lock=True)
    close_round(s, session, "user", now)
    return session


def close_if_due(s: Session, session_id: str, now: datetime | None = None) -> bool:
    """Close the open round when its time is up (checked lazily on reads); True if closed."""
    now = now or utcnow()
    session = get_session(s, session_id, lock=True)
    if not round_due(session, now):
        return False
    close_round(s, session, "time", now)
    return True


def finish_training(
    s: Session,
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
    current = get_round(s, session.id, session.round)
    current.stats = dict(stats)
    s.add(CheckpointRow(round_id=current.id, path=checkpoint, created_at=now))
    rounds = int(session.settings.get("rounds", 1))
    if session.round + 1 < rounds:
        session.round += 1
        session.phase = PREPARING
        s.add(_new_round(session.id, session.round))
        _set_progress(session, "queued", 0.0, f"round {session.round}: waiting for the worker")
    elif session.settings.get("driver") == LIBRARY:  # the program trains its agent itself
        session.phase = FINISHED
        _set_progress(session, "finished", 1.0, "all rounds are done")
    else:
        start_final(s, session, settings_of(session).final_ppo_steps, "final", now)
    session.failed_phase = None
    session.error = None
    touch(session, now)
    return True


def start_final(
    s: Session, session: SessionRow, steps: int, reason: str, now: datetime | None = None
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
    _set_progress(session, "queued", 0.0, "final training: waiting for the worker")
    touch(session, now)


def finish_final(
    s: Session,
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
    session.phase = FINISHED
    session.failed_phase = None
    session.error = None
    _set_progress(session, "finished", 1.0, "the final agent is ready")
    touch(session, now)
    return True


def mark_failed(
    s: Session, session_id: str, phase: str, error: str, now: datetime | None = None
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


def retry(s: Session, session_id: str, now: datetime | None = None) -> SessionRow:
    """Re-queue the failed step. Raises ConflictError unless the session failed."""
    session = get_session(s, session_id, lock=True)
    if session.phase != FAILED or session.failed_phase not in WORK_PHASES:
        raise ConflictError(f"session {session_id} has not failed; it is {session.phase}")
    session.phase = session.failed_phase
    session.failed_phase = None
    session.error = None
    _set_progress(session, "queued", 0.0, "retrying: waiting for the training worker")
    touch(session, now)
    return session


def set_progress(
    s: Session,
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
    _set_progress(session, phase, fraction, message)
    touch(session, now)
    return True


def _set_progress(session: SessionRow, phase: str, fraction: float, message: str) -> None:
    session.progress_phase = phase
    session.progress_fraction = float(min(1.0, max(0.0, fraction)))
    session.progress_message = message


# ------------------------------------------------------------------ counts


def counts(s: Session, session: SessionRow) -> Counts:
    """Judgements (not undone) and their pairs, this round and in total."""
    live = (JudgementRow.session_id == session.id, JudgementRow.undone.is_(False))
    judged: dict[int, int] = {
        r: n
        for r, n in s.execute(
            select(JudgementRow.round_index, func.count(JudgementRow.id))
            .where(*live)
            .group_by(JudgementRow.round_index)
        ).all()
    }
    paired: dict[int, int] = {
        r: n
        for r, n in s.execute(
            select(JudgementRow.round_index, func.count(PairRow.id))
            .join(PairRow, PairRow.judgement_id == JudgementRow.id)
            .where(*live)
            .group_by(JudgementRow.round_index)
        ).all()
    }
    return Counts(
        comparisons_round=judged.get(session.round, 0),
        pairs_round=paired.get(session.round, 0),
        comparisons_total=sum(judged.values()),
        pairs_total=sum(paired.values()),
    )
