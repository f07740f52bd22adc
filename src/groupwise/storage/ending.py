"""The end of a session: "Finish now" and "Continue training" (docs/app.md, "Session end").

After its last round a session trains PPO further on the frozen learned reward in a round
without feedback (`lifecycle.start_final`, phase ``finishing``) and then shows the final
agent (``finished``). A person may end the session early, and continue a finished one:

- `finish_now`: no more rounds after the current one. An open round ends now and is
  trained on what was answered, a round in training finishes its training, a round being
  prepared is dropped; then the final phase.
- `continue_training`: a finished session trains again, either `steps` more PPO steps on
  the frozen reward (another round without feedback) or `rounds` more feedback rounds
  (followed by the final phase again).

Like `groupwise.storage.lifecycle`, every function takes an open `DbSession` and leaves
committing to the caller.
"""

from datetime import datetime

from sqlalchemy import select
from sqlalchemy.orm import Session as DbSession

from groupwise.storage.errors import ConflictError, InvalidError
from groupwise.storage.lifecycle import close_round, start_final
from groupwise.storage.models import CheckpointRow, RoundRow, SessionRow, utcnow
from groupwise.storage.phases import FINISHED, PREPARING, READY, TRAINING
from groupwise.storage.progress import write_progress
from groupwise.storage.sessions import get_round, get_session, new_round, settings_of, touch
from groupwise.storage.settings import LIBRARY, MAX_ROUNDS


def finish_now(s: DbSession, session_id: str, now: datetime | None = None) -> SessionRow:
    """End the session after its current round (module docstring).

    Raises:
        NotFoundError: no such session.
        ConflictError: the session is finishing, finished or failed, is driven by a
            program (`WebTeacher`), or has no answered round yet to finish from.
    """
    now = now or utcnow()
    session = get_session(s, session_id, lock=True)
    _require_app(session, "finish it")
    r = session.round
    if session.phase == READY:
        _set_rounds(session, r + 1)
        close_round(s, session, "user", now)
    elif session.phase == TRAINING:
        _set_rounds(session, r + 1)  # `finish_training` then starts the final phase
        touch(session, now)
    elif session.phase == PREPARING:
        if r == 0:
            raise ConflictError(
                f"cannot finish session {session_id}: round 0 is being prepared and nothing "
                "has been learned yet; answer round 0 first"
            )
        s.delete(get_round(s, session_id, r))
        s.flush()
        session.round = r - 1
        _set_rounds(session, r)
        start_final(s, session, settings_of(session).final_ppo_steps, "final", now)
    else:
        raise ConflictError(f"cannot finish session {session_id}: it is {session.phase}")
    return session


def continue_training(
    s: DbSession,
    session_id: str,
    *,
    steps: int | None = None,
    rounds: int | None = None,
    now: datetime | None = None,
) -> SessionRow:
    """Train a finished session again: `steps` more PPO steps on the frozen learned reward,
    or `rounds` more feedback rounds (exactly one of them, positive).

    Raises:
        NotFoundError: no such session.
        ConflictError: the session is not finished, is driven by a program, or has no
            trained agent (an imported session).
        InvalidError: neither or both given, or more rounds than a session may have.
    """
    if (steps is None) == (rounds is None):
        raise InvalidError("give either steps or rounds to continue training")
    now = now or utcnow()
    session = get_session(s, session_id, lock=True)
    _require_app(session, "continue training")
    if session.phase != FINISHED:
        raise ConflictError(
            f"cannot continue session {session_id}: it is {session.phase}; a session "
            "continues once it is finished"
        )
    if not _has_checkpoint(s, session_id):
        raise ConflictError(f"session {session_id} has no trained agent to continue")
    if steps is not None:
        start_final(s, session, steps, "continue", now)
        return session
    assert rounds is not None
    following = session.round + 1
    if following + rounds > MAX_ROUNDS:
        raise InvalidError(
            f"session {session_id} would reach round {following + rounds - 1}; a session "
            f"has at most {MAX_ROUNDS} rounds (0–{MAX_ROUNDS - 1})"
        )
    _set_rounds(session, following + rounds)
    session.round = following
    session.phase = PREPARING
    s.add(new_round(session.id, following))
    write_progress(session, "queued", 0.0, f"round {following}: waiting for the worker")
    touch(session, now)
    return session


def _require_app(session: SessionRow, action: str) -> None:
    if session.settings.get("driver") == LIBRARY:
        raise ConflictError(
            f"cannot {action}: session {session.id} is driven by a program (WebTeacher)"
        )


def _set_rounds(session: SessionRow, rounds: int) -> None:
    """The round index at which the final phase starts (`SessionSettings.rounds`)."""
    session.settings = {**session.settings, "rounds": rounds}


def _has_checkpoint(s: DbSession, session_id: str) -> bool:
    query = (
        select(CheckpointRow.id)
        .join(RoundRow, CheckpointRow.round_id == RoundRow.id)
        .where(RoundRow.session_id == session_id)
        .limit(1)
    )
    return s.scalars(query).first() is not None


def frozen_rounds(s: DbSession, session_id: str) -> set[int]:
    """The indices of the session's rounds without feedback (PPO on the frozen reward)."""
    query = select(RoundRow.index).where(
        RoundRow.session_id == session_id, RoundRow.frozen_steps.is_not(None)
    )
    return set(s.scalars(query))
