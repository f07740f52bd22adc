"""Rounds prepared ahead (continuous training, issue 24): the next round waits in the
database and opens in the same transaction that ends the round before it.

While a person compares in round r of a continuous session, the worker samples round r + 1
from the current policy, renders its clips and keeps the result here (`stage_round`). When
round r ends — the person's "End round", its comparison budget or its timer —
`lifecycle.close_round` opens round r + 1 at once (`open_staged`), so the answer to "End
round" already shows the next round; the worker commits round r (final fit, evaluation,
checkpoint) afterwards, and a worker killed meanwhile commits it when it resumes
(`lifecycle.uncommitted_round`). A round ended before its successor was staged goes the
rounds-mode way (phase ``training``): the worker's training job opens the staged round as
soon as it is ready.
"""

import dataclasses
from datetime import datetime
from typing import Any

from sqlalchemy import JSON, ForeignKey, Integer, UniqueConstraint, delete, select
from sqlalchemy.orm import Mapped, mapped_column
from sqlalchemy.orm import Session as DbSession

from groupwise.storage.lifecycle import advance_before_commit
from groupwise.storage.models import Base, utcnow
from groupwise.storage.phases import READY, TRAINING
from groupwise.storage.rounds import (
    BehaviourInput,
    GroupSuggestionInput,
    PairInput,
    PreparedRound,
    store_prepared_round,
)
from groupwise.storage.sessions import get_session


class StagedRoundRow(Base):
    """Round `round_index` of a session, prepared ahead and not open yet."""

    __tablename__ = "staged_rounds"
    __table_args__ = (UniqueConstraint("session_id", "round_index"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    session_id: Mapped[str] = mapped_column(
        ForeignKey("sessions.id", ondelete="CASCADE"), index=True
    )
    round_index: Mapped[int] = mapped_column(Integer)
    prepared: Mapped[dict[str, Any]] = mapped_column(JSON)
    created_at: Mapped[datetime] = mapped_column(default=utcnow)


def stage_round(s: DbSession, session_id: str, round_index: int, prepared: PreparedRound) -> bool:
    """Keep `prepared` as round `round_index` until the round before it ends (replacing an
    earlier staging of it); False (nothing written) when the session has moved past the
    round before (it opened `round_index` some other way, or finished)."""
    session = get_session(s, session_id, lock=True)
    if session.round != round_index - 1 or session.phase not in (READY, TRAINING):
        return False
    _drop(s, session_id, round_index)
    s.add(
        StagedRoundRow(
            session_id=session_id, round_index=round_index, prepared=dataclasses.asdict(prepared)
        )
    )
    s.flush()
    return True


def open_staged(s: DbSession, session_id: str, round_index: int) -> bool:
    """Round `round_index` has just ended (phase ``training``): open round `round_index + 1`
    from its staged offer, if there is one and it is not past the last round; True when it
    opened. The ended round's training is left for the worker to record."""
    row = s.scalar(
        select(StagedRoundRow).where(
            StagedRoundRow.session_id == session_id,
            StagedRoundRow.round_index == round_index + 1,
        )
    )
    if row is None:
        return False
    prepared = _prepared(row.prepared)
    s.delete(row)
    return advance_before_commit(s, session_id, round_index) and store_prepared_round(
        s, session_id, round_index + 1, prepared
    )


def staged_rounds(s: DbSession, session_id: str) -> list[int]:
    """The indices of a session's rounds waiting staged."""
    return list(
        s.scalars(
            select(StagedRoundRow.round_index)
            .where(StagedRoundRow.session_id == session_id)
            .order_by(StagedRoundRow.round_index)
        )
    )


def _drop(s: DbSession, session_id: str, round_index: int) -> None:
    s.execute(
        delete(StagedRoundRow).where(
            StagedRoundRow.session_id == session_id, StagedRoundRow.round_index == round_index
        )
    )


def _prepared(data: dict[str, Any]) -> PreparedRound:
    return PreparedRound(
        behaviours=tuple(BehaviourInput(**b) for b in data["behaviours"]),
        suggestions=tuple(
            GroupSuggestionInput(**{**g, "left": tuple(g["left"]), "right": tuple(g["right"])})
            for g in data["suggestions"]
        ),
        edges=tuple(PairInput(**e) for e in data["edges"]),
        queue=tuple(PairInput(**q) for q in data["queue"]),
    )
