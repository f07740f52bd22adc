"""Judgements as records: the stored comparisons with their pairs, listed for the page, the
event stream and the export, and as the round's end trains on them (`round_judgements`).

Storing, retrying and undoing a comparison is `storage.judging`. A judgement's key in its
round is its place among all the round's judgements, undone ones included: the key its
pairs were derived with (`groupwise.preferences.pairs.judgement_pairs`), so the pairs
stored and shown are the pairs trained on.
"""

from dataclasses import dataclass
from datetime import datetime

from sqlalchemy import select
from sqlalchemy.orm import Session as DbSession
from sqlalchemy.orm import selectinload

from groupwise.episodes.ids import behaviour_index
from groupwise.preferences.judgement import EQUAL, LEFT_BETTER, RIGHT_BETTER, Judgement, Source
from groupwise.storage.annotators import OWNER
from groupwise.storage.models import MAX_INTEGER, JudgementRow
from groupwise.storage.sessions import get_session

LABELS: dict[str, float] = {"left": LEFT_BETTER, "right": RIGHT_BETTER, "equal": EQUAL}
"""The page's label → P(left group preferred)."""
SOURCES = ("suggested", "explored", "pairwise")


@dataclass(frozen=True)
class PairRecord:
    """A preference pair over behaviour names; `label` = P(a preferred)."""

    a: str
    b: str
    label: float


@dataclass(frozen=True)
class JudgementRecord:
    """A stored judgement with its derived pairs (none once undone)."""

    id: int
    session_id: str
    seq: int
    client_id: str
    round: int
    left: tuple[str, ...]
    right: tuple[str, ...]
    label: str
    source: str
    seconds: float
    edits: int
    annotator: str
    created_at: datetime
    undone: bool
    revision: int
    pairs: tuple[PairRecord, ...]
    annotator_id: str = OWNER
    """Who made it: "owner" or an annotator's id."""
    suggestion_id: int | None = None
    """The group suggestion it answered, if any."""


def record_of(row: JudgementRow) -> JudgementRecord:
    """The frozen record of a judgement row (its pairs must be loaded)."""
    return JudgementRecord(
        id=row.id,
        session_id=row.session_id,
        seq=row.seq,
        client_id=row.client_id,
        round=row.round_index,
        left=tuple(row.left),
        right=tuple(row.right),
        label=row.label,
        source=row.source,
        seconds=row.seconds,
        edits=row.edits,
        annotator=row.annotator,
        created_at=row.created_at,
        undone=row.undone,
        revision=row.revision,
        pairs=tuple(PairRecord(p.a, p.b, p.label) for p in row.pairs),
        annotator_id=row.annotator_id or OWNER,
        suggestion_id=row.suggestion_id,
    )


def list_judgements(
    s: DbSession,
    session_id: str,
    round_index: int | None = None,
    *,
    include_undone: bool = False,
    after_revision: int | None = None,
) -> list[JudgementRecord]:
    """A session's judgements, oldest first; optionally one round's, or only those changed
    after `after_revision` (the event stream's query). Raises NotFoundError."""
    get_session(s, session_id)
    query = (
        select(JudgementRow)
        .where(JudgementRow.session_id == session_id)
        .options(selectinload(JudgementRow.pairs))
        .order_by(JudgementRow.seq)
    )
    if round_index is not None:
        query = query.where(JudgementRow.round_index == round_index)
    if not include_undone:
        query = query.where(JudgementRow.undone.is_(False))
    if after_revision is not None:
        query = (
            query.where(JudgementRow.revision > min(after_revision, MAX_INTEGER))
            .order_by(None)
            .order_by(JudgementRow.revision)
        )
    return [record_of(row) for row in s.scalars(query)]


def round_judgements(
    s: DbSession, session_id: str, round_index: int
) -> list[tuple[int, Judgement]]:
    """The round's judgements that were not undone, as (key, judgement): the key is the
    judgement's place among all the round's judgements, undone ones included (what its
    pairs were derived with), the groups pool indices."""
    rows = list_judgements(s, session_id, round_index, include_undone=True)
    return [
        (
            key,
            Judgement(
                left=tuple(behaviour_index(name) for name in r.left),
                right=tuple(behaviour_index(name) for name in r.right),
                label=LABELS[r.label],
                source=Source(r.source) if r.source in SOURCES else Source.EXPLORED,
                seconds=r.seconds,
                edits=r.edits,
                annotator=r.annotator,
            ),
        )
        for key, r in enumerate(rows)
        if not r.undone
    ]
