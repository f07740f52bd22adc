"""Judging: storing a comparison with its preference pairs, answering its retry, undoing it.

`add_judgement` is the write path of every comparison: it validates the groups against the
open round, derives the preference pairs (SPEC §6, the session's `pair_derivation`) and
adds judgement and pairs in the caller's transaction, which commits before the HTTP answer
is sent, so an answered judgement survives a crash. A retry with the same `client_id`
returns the stored judgement instead of storing it twice.

Pairs are the round's own: judgement number k of a round (0, 1, … in arrival order, undone
ones included) gets the pairs `groupwise.preferences.pairs.judgement_pairs` derives for key
k, the one derivation that the round's end (`groupwise.run.round.end_round`, on
`storage.judgements.round_judgements`) calls again, so the pairs stored and shown are the
pairs trained on.

Every judgement is someone's (docs/teams.md): `JudgementInput.annotator_id` names the
annotator who made it (`storage.annotators`; "owner" for the session's owner), and only
they can undo it. The stored judgements are read back with `storage.judgements`.
"""

from collections.abc import Sequence
from dataclasses import dataclass
from datetime import datetime

from sqlalchemy import func, select
from sqlalchemy.orm import Session as DbSession
from sqlalchemy.orm import selectinload

from groupwise.episodes.ids import behaviour_id
from groupwise.preferences.judgement import MAX_GROUP, Judgement
from groupwise.preferences.pairs import judgement_pairs
from groupwise.storage.annotators import OWNER, list_annotators, maker_name
from groupwise.storage.errors import (
    ConflictError,
    ForbiddenError,
    InvalidError,
    NotFoundError,
    check_text,
)
from groupwise.storage.judgements import LABELS, SOURCES, JudgementRecord, record_of
from groupwise.storage.lifecycle import close_round
from groupwise.storage.models import (
    MAX_INTEGER,
    BehaviourRow,
    JudgementRow,
    PairRow,
    SessionRow,
    utcnow,
)
from groupwise.storage.phases import READY
from groupwise.storage.rounds import Overlap, mark_suggestion_used
from groupwise.storage.sessions import get_round, get_session, settings_of, touch
from groupwise.storage.timer import round_due

MAX_GROUP_BY_MODE = {"groupwise": MAX_GROUP, "pairwise": 1}


@dataclass(frozen=True)
class JudgementInput:
    """A comparison as the page sends it (`JudgementIn`)."""

    client_id: str
    round: int
    left: tuple[str, ...]
    right: tuple[str, ...]
    label: str  # "left" | "right" | "equal"
    source: str  # "suggested" | "explored" | "pairwise"
    seconds: float = 0.0
    edits: int = 0
    annotator: str = ""
    """The name it is stored under (the annotator's; the owner's free text)."""
    annotator_id: str = OWNER
    """Who makes it: "owner" or an annotator's id (`storage.annotators`)."""


def add_judgement(
    s: DbSession, session_id: str, judgement: JudgementInput, now: datetime | None = None
) -> tuple[JudgementRecord, bool]:
    """Store a judgement and its pairs; (record, True) when new, (stored, False) on a retry.

    A retry (same `client_id`) returns the stored judgement, whatever the session's state
    now. When the round's comparison budget is reached, the round closes in the same
    transaction.

    Raises:
        NotFoundError: unknown session.
        ConflictError: the session is not ready, the round is not the open one or its
            time is up, or the `client_id` was used for a different comparison (or by
            someone else).
        InvalidError: a behaviour not in the round, in both groups or twice in one; an
            empty group or one too large for the mode; an unknown label or source; a NUL
            character in the client id or annotator (`check_text`).
    """
    now = now or utcnow()
    check_text("client_id", judgement.client_id)
    check_text("annotator", judgement.annotator)
    session = get_session(s, session_id, lock=True)
    stored = _by_client_id(s, session_id, judgement.client_id)
    if stored is not None:
        if (stored.round, stored.left, stored.right, stored.label, stored.annotator_id) != (
            judgement.round,
            tuple(judgement.left),
            tuple(judgement.right),
            judgement.label,
            judgement.annotator_id,
        ):
            raise ConflictError(
                f"client_id {judgement.client_id!r} was already used for another comparison"
            )
        return stored, False
    _check_open(session, judgement.round, now)
    round_row = get_round(s, session_id, judgement.round)
    indices = _check_groups(s, session, round_row.id, judgement)
    seq = session.judgement_seq
    session.judgement_seq += 1
    settings = settings_of(session)
    derived = judgement_pairs(
        Judgement(indices[0], indices[1], LABELS[judgement.label]),
        settings.pair_derivation,
        settings.pair_oversample,
        seed=settings.seed,
        round_index=judgement.round,
        key=_given_in_round(s, session_id, judgement.round),
    )
    touch(session, now)
    row = JudgementRow(
        session_id=session_id,
        round_id=round_row.id,
        round_index=judgement.round,
        seq=seq,
        client_id=judgement.client_id,
        left=list(judgement.left),
        right=list(judgement.right),
        label=judgement.label,
        source=judgement.source,
        seconds=float(judgement.seconds),
        edits=int(judgement.edits),
        annotator=judgement.annotator,
        annotator_id=None if judgement.annotator_id == OWNER else judgement.annotator_id,
        created_at=now,
        revision=session.revision,
        pairs=[
            PairRow(position=i, a=behaviour_id(p.a), b=behaviour_id(p.b), label=p.label)
            for i, p in enumerate(derived)
        ],
    )
    s.add(row)
    s.flush()
    shared = bool(list_annotators(s, session_id))  # someone else could answer it too
    row.suggestion_id = mark_suggestion_used(
        s,
        round_row.id,
        judgement.left,
        judgement.right,
        judgement.source,
        holder=judgement.annotator_id,
        overlap=Overlap(settings.overlap_share, settings.seed, judgement.round) if shared else None,
    )
    limit = settings.comparisons_per_round
    if limit > 0 and _live_in_round(s, session_id, judgement.round) >= limit:
        close_round(s, session, "comparisons", now)
    return record_of(row), True


def _by_client_id(s: DbSession, session_id: str, client_id: str) -> JudgementRecord | None:
    row = s.scalars(
        select(JudgementRow)
        .where(JudgementRow.session_id == session_id, JudgementRow.client_id == client_id)
        .options(selectinload(JudgementRow.pairs))
    ).one_or_none()
    return None if row is None else record_of(row)


def _check_open(session: SessionRow, round_index: int, now: datetime) -> None:
    if session.phase != READY:
        raise ConflictError(
            f"session {session.id} is {session.phase}; judgements are taken only while a "
            "round is open"
        )
    if round_index != session.round:
        state = "closed" if round_index < session.round else "not open yet"
        raise ConflictError(f"round {round_index} is {state}; the open round is {session.round}")
    if round_due(session, now):  # closed lazily by the next read or the supervisor
        raise ConflictError(f"the time of round {round_index} is up")


def _check_groups(
    s: DbSession, session: SessionRow, round_id: int, judgement: JudgementInput
) -> tuple[tuple[int, ...], tuple[int, ...]]:
    if judgement.label not in LABELS:
        raise InvalidError(f"label must be one of {', '.join(LABELS)}, got {judgement.label!r}")
    if judgement.source not in SOURCES:
        raise InvalidError(f"source must be one of {', '.join(SOURCES)}, got {judgement.source!r}")
    largest = MAX_GROUP_BY_MODE[session.mode]
    for side, group in (("left", judgement.left), ("right", judgement.right)):
        if not group:
            raise InvalidError(f"the {side} group is empty")
        if len(group) > largest:
            raise InvalidError(
                f"the {side} group has {len(group)} behaviours; a {session.mode} comparison "
                f"allows at most {largest}"
            )
        if len(set(group)) != len(group):
            raise InvalidError(f"the {side} group lists a behaviour twice")
    both = sorted(set(judgement.left) & set(judgement.right))
    if both:
        raise InvalidError(f"{', '.join(both)} cannot be in both groups")
    known = _behaviour_indices(s, round_id, [*judgement.left, *judgement.right])
    unknown = [name for name in (*judgement.left, *judgement.right) if name not in known]
    if unknown:
        what = "is not a behaviour" if len(unknown) == 1 else "are not behaviours"
        raise InvalidError(f"{', '.join(unknown)} {what} of round {judgement.round}")
    return (
        tuple(known[name] for name in judgement.left),
        tuple(known[name] for name in judgement.right),
    )


def _behaviour_indices(s: DbSession, round_id: int, names: Sequence[str]) -> dict[str, int]:
    rows = s.execute(
        select(BehaviourRow.name, BehaviourRow.index).where(
            BehaviourRow.round_id == round_id, BehaviourRow.name.in_(set(names))
        )
    ).all()
    return {name: index for name, index in rows}


def _given_in_round(s: DbSession, session_id: str, round_index: int) -> int:
    """Judgements given in the round so far, undone ones included."""
    return int(
        s.scalar(
            select(func.count())
            .select_from(JudgementRow)
            .where(JudgementRow.session_id == session_id, JudgementRow.round_index == round_index)
        )
        or 0
    )


def _live_in_round(s: DbSession, session_id: str, round_index: int) -> int:
    return int(
        s.scalar(
            select(func.count(JudgementRow.id)).where(
                JudgementRow.session_id == session_id,
                JudgementRow.round_index == round_index,
                JudgementRow.undone.is_(False),
            )
        )
        or 0
    )


def undo_judgement(
    s: DbSession,
    session_id: str,
    judgement_id: int,
    now: datetime | None = None,
    *,
    annotator_id: str = OWNER,
) -> JudgementRecord:
    """Undo a judgement of the open round: its pairs are deleted, the row stays (undone).

    Only the annotator who made it (`annotator_id`: "owner" or an annotator's id) can
    undo it. Undoing an undone judgement returns it unchanged.

    Raises:
        NotFoundError: unknown session, or no such judgement in it.
        ForbiddenError: someone else made it.
        ConflictError: the judgement's round is closed.
    """
    now = now or utcnow()
    session = get_session(s, session_id, lock=True)
    row = None
    if 0 <= judgement_id <= MAX_INTEGER:
        row = s.scalars(
            select(JudgementRow)
            .where(JudgementRow.id == judgement_id, JudgementRow.session_id == session_id)
            .options(selectinload(JudgementRow.pairs))
        ).one_or_none()
    if row is None:
        raise NotFoundError(f"session {session_id} has no judgement {judgement_id}")
    if (row.annotator_id or OWNER) != annotator_id:
        maker = maker_name(s, session, row.annotator_id, row.annotator)
        raise ForbiddenError(f"judgement {judgement_id} was made by {maker}; only they can undo it")
    if row.undone:
        return record_of(row)
    if session.phase != READY or row.round_index != session.round:
        raise ConflictError(
            f"judgement {judgement_id} is in round {row.round_index}, which is closed; only "
            "judgements of the open round can be undone"
        )
    row.undone = True
    row.undone_at = now
    row.pairs.clear()
    touch(session, now)
    row.revision = session.revision
    s.flush()
    return record_of(row)
