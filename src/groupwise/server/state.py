"""Sessions as the page sees them: `SessionState`, creation, and the lifecycle actions.

Every read checks the round timer lazily: a round whose time budget is used up is closed
(phase ``training``) before its state is returned, so the page never sees an open round
that should have ended (the supervisor also checks, for sessions nobody is looking at).
"""

from datetime import datetime

import numpy as np
from sqlalchemy.orm import Session as DbSession

from groupwise.envs import horizon
from groupwise.envs.episodes import check_episode_length
from groupwise.server import schemas
from groupwise.server.context import AppContext
from groupwise.storage import Database, InvalidError, lifecycle, sessions, timer
from groupwise.storage.counts import Counts, counts
from groupwise.storage.judgements import JudgementRecord
from groupwise.storage.models import SessionRow, utcnow
from groupwise.storage.settings import SessionSettings


def state_of(
    session: SessionRow, counted: Counts, now: datetime, shown_at: datetime | None = None
) -> schemas.SessionState:
    """The `SessionState` of a session row (`shown_at`: its current round's)."""
    settings = SessionSettings.model_validate(session.settings)
    return schemas.SessionState(
        id=session.id,
        env=session.env,
        mode=session.mode,  # type: ignore[arg-type]  # one of MODES, checked on creation
        settings=settings,
        annotator=session.annotator,
        round=session.round,
        rounds=settings.rounds,
        phase=session.phase,  # type: ignore[arg-type]  # one of PHASES
        progress=schemas.Progress(
            phase=session.progress_phase,
            fraction=session.progress_fraction,
            message=session.progress_message,
        ),
        error=session.error,
        failed_phase=session.failed_phase if session.phase == "failed" else None,  # type: ignore[arg-type]  # one of WORK_PHASES
        timer=schemas.Timer(
            elapsed_s=round(timer.elapsed(session, now), 3),
            budget_s=settings.round_seconds,
            paused=session.paused,
            running=session.timer_started_at is not None,
            shown_at=shown_at,
        ),
        counts=schemas.Counts(
            comparisons_round=counted.comparisons_round,
            pairs_round=counted.pairs_round,
            comparisons_total=counted.comparisons_total,
            pairs_total=counted.pairs_total,
        ),
        created_at=session.created_at,
        origin=session.origin,
    )


def close_if_due(db: Database, session_id: str) -> int:
    """Close the session's round if its time is up; the session's revision after that.

    Raises NotFoundError.
    """
    with db.read() as s:
        session = sessions.get_session(s, session_id)
        if not timer.round_due(session):
            return session.revision
    with db.write() as s:
        lifecycle.close_if_due(s, session_id)
        return sessions.get_session(s, session_id).revision


def _state(s: DbSession, session: SessionRow, now: datetime) -> schemas.SessionState:
    return state_of(session, counts(s, session), now, timer.shown_at(s, session))


def read_state(db: Database, session_id: str) -> schemas.SessionState:
    """The session's current state. Raises NotFoundError."""
    close_if_due(db, session_id)
    with db.read() as s:
        return _state(s, sessions.get_session(s, session_id), utcnow())


def list_states(db: Database) -> list[schemas.SessionState]:
    """Every session's state, newest first."""
    now = utcnow()
    with db.read() as s:
        return [_state(s, row, now) for row in sessions.list_sessions(s)]


def check_env(env: str, settings: SessionSettings) -> SessionSettings:
    """The settings a new session of `env` stores (`SessionSettings.for_env`: its L in
    steps). Raises InvalidError unless `env` is known, can be made here, its horizon holds a
    behaviour, and a random policy's episodes last long enough to hold one
    (`envs.episodes.check_episode_length`)."""
    try:
        steps = horizon(env)
        resolved = settings.for_env(env)  # makes the env once, for its step duration
    except ValueError as error:
        raise InvalidError(str(error)) from None
    except Exception as error:
        # A registered id runs its own constructor, which fails its own way (e.g. Gymnasium's
        # DependencyNotInstalled for CarRacing-v3 without Box2D): the id is the person's error.
        raise InvalidError(f"env {env!r} cannot be made here: {error}") from None
    length = resolved.fragment_length
    seconds = resolved.clip_timing(env).seconds
    if steps is None or length is None or steps < length:
        raise InvalidError(
            f"env {env} needs a fixed horizon of at least fragment_length = {length} steps "
            f"({seconds:.3g} s); it has {steps}"
        )
    try:  # an env that ends episodes early (issue 23): round 0 would fail, and every retry
        window = f" (clip_seconds = {seconds:.3g} s)"
        check_episode_length(env, length, np.random.default_rng(resolved.seed), window)
    except ValueError as error:
        raise InvalidError(str(error)) from None
    return resolved


def create_session(context: AppContext, request: schemas.SessionCreate) -> schemas.SessionState:
    """Create a session (its round 0 is queued for the worker). Raises InvalidError."""
    settings = check_env(request.env, request.settings)
    with context.db.write() as s:
        session = sessions.create_session(s, request.env, request.mode, settings, request.annotator)
        session_id = session.id
    context.supervisor.ensure_worker_soon()
    return read_state(context.db, session_id)


def pause(db: Database, session_id: str) -> schemas.SessionState:
    with db.write() as s:
        timer.pause(s, session_id)
    return read_state(db, session_id)


def show_round(db: Database, session_id: str, round_index: int) -> schemas.SessionState:
    """A page shows the open round: its timer starts the first time. Raises NotFoundError,
    ConflictError."""
    with db.write() as s:
        timer.show_round(s, session_id, round_index)
    return read_state(db, session_id)


def resume(db: Database, session_id: str) -> schemas.SessionState:
    with db.write() as s:
        timer.resume(s, session_id)
    return read_state(db, session_id)


def end_round(context: AppContext, session_id: str) -> schemas.SessionState:
    with context.db.write() as s:
        lifecycle.end_round(s, session_id)
    context.supervisor.ensure_worker_soon()
    return read_state(context.db, session_id)


def retry(context: AppContext, session_id: str) -> schemas.SessionState:
    """Re-queue the failed step and make sure a worker runs. Raises ConflictError."""
    with context.db.write() as s:
        lifecycle.retry(s, session_id)
    context.supervisor.ensure_worker_soon()
    return read_state(context.db, session_id)


def judgement_out(record: JudgementRecord) -> schemas.JudgementOut:
    """The page's view of a stored judgement."""
    return schemas.JudgementOut(
        id=record.id,
        client_id=record.client_id,
        round=record.round,
        left=list(record.left),
        right=list(record.right),
        label=record.label,  # type: ignore[arg-type]  # validated on storing
        source=record.source,
        seconds=record.seconds,
        edits=record.edits,
        annotator=record.annotator,
        created_at=record.created_at,
        undone=record.undone,
        pairs=[schemas.PairOut(a=p.a, b=p.b, label=p.label) for p in record.pairs],
    )
