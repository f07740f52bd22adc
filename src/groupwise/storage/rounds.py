"""A round's pool in the database: behaviours, group suggestions, edges, the pairwise queue.

The worker computes a round (`groupwise.worker.jobs`) and stores it in one transaction with
`store_prepared_round`, which also opens the round; everything else here reads it.
"""

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from datetime import datetime

from sqlalchemy import delete, select
from sqlalchemy.orm import Session as DbSession

from groupwise.pool.ids import behaviour_id
from groupwise.storage.errors import NotFoundError
from groupwise.storage.lifecycle import open_round
from groupwise.storage.models import (
    BehaviourRow,
    JudgementRow,
    PairQueueRow,
    RoundRow,
    SuggestionEdgeRow,
    SuggestionRow,
)
from groupwise.storage.phases import PREPARING
from groupwise.storage.sessions import get_round, get_session


@dataclass(frozen=True)
class BehaviourInput:
    """Behaviour `index` of a pool: its name ("b<index>"), clip and poster ids."""

    index: int
    clip: str
    poster: str
    true_return: float | None

    @property
    def name(self) -> str:
        return behaviour_id(self.index)


@dataclass(frozen=True)
class GroupSuggestionInput:
    """A suggested comparison of two tree nodes' behaviours (best first in a list)."""

    left: tuple[str, ...]
    right: tuple[str, ...]
    left_node: str
    right_node: str
    score: float


@dataclass(frozen=True)
class PairInput:
    """A pair of behaviour names with a score (an edge, or an entry of the pairwise queue)."""

    a: str
    b: str
    score: float


@dataclass(frozen=True)
class PreparedRound:
    """Everything the worker computed for a round, in display order."""

    behaviours: tuple[BehaviourInput, ...]
    suggestions: tuple[GroupSuggestionInput, ...]
    edges: tuple[PairInput, ...]  # top-k pairwise edges, best first, score in (0, 1]
    queue: tuple[PairInput, ...]  # the pairwise baseline's pairs, asked in this order


def store_prepared_round(
    s: DbSession,
    session_id: str,
    round_index: int,
    prepared: PreparedRound,
    now: datetime | None = None,
) -> bool:
    """Store round `round_index`'s pool and open the round; False (nothing stored) when the
    session is no longer preparing that round (e.g. marked failed meanwhile)."""
    session = get_session(s, session_id, lock=True)
    if session.phase != PREPARING or session.round != round_index:
        return False
    row = get_round(s, session_id, round_index)
    for table in (BehaviourRow, SuggestionRow, SuggestionEdgeRow, PairQueueRow):
        s.execute(delete(table).where(table.round_id == row.id))
    s.add_all(
        BehaviourRow(
            round_id=row.id,
            name=b.name,
            index=b.index,
            clip=b.clip,
            poster=b.poster,
            true_return=b.true_return,
        )
        for b in prepared.behaviours
    )
    s.add_all(
        SuggestionRow(
            round_id=row.id,
            rank=rank,
            left=list(g.left),
            right=list(g.right),
            left_node=g.left_node,
            right_node=g.right_node,
            score=g.score,
            key=query_key(g.left, g.right),
        )
        for rank, g in enumerate(prepared.suggestions)
    )
    s.add_all(
        SuggestionEdgeRow(round_id=row.id, rank=rank, a=e.a, b=e.b, score=e.score)
        for rank, e in enumerate(prepared.edges)
    )
    s.add_all(
        PairQueueRow(round_id=row.id, position=i, a=p.a, b=p.b, score=p.score)
        for i, p in enumerate(prepared.queue)
    )
    open_round(s, session, now)
    s.flush()
    return True


def behaviours(s: DbSession, round_id: int) -> list[BehaviourRow]:
    """The pool of a round, by index."""
    return list(
        s.scalars(
            select(BehaviourRow)
            .where(BehaviourRow.round_id == round_id)
            .order_by(BehaviourRow.index)
        )
    )


def compared(s: DbSession, round_row: RoundRow) -> list[str]:
    """Names of the behaviours in a live judgement of the round, in first-compared order."""
    seen: dict[str, None] = {}
    for left, right in s.execute(
        select(JudgementRow.left, JudgementRow.right)
        .where(JudgementRow.round_id == round_row.id, JudgementRow.undone.is_(False))
        .order_by(JudgementRow.seq)
    ).all():
        seen.update(dict.fromkeys([*left, *right]))
    return list(seen)


def edges(s: DbSession, round_id: int, k: int) -> list[SuggestionEdgeRow]:
    """The round's `k` best pairwise suggestion edges, best first."""
    return list(
        s.scalars(
            select(SuggestionEdgeRow)
            .where(SuggestionEdgeRow.round_id == round_id)
            .order_by(SuggestionEdgeRow.rank)
            .limit(max(0, k))
        )
    )


EDITED_SCAN = 200
"""An edited suggestion is looked for among this many best unused suggestions."""


def query_key(left: Iterable[str], right: Iterable[str]) -> str:
    """One string for a comparison of two groups: equal for the same groups in any order."""
    sides = sorted(",".join(sorted(group)) for group in (left, right))
    return "|".join(sides)


def next_suggestion(
    s: DbSession, round_id: int, exclude: Sequence[tuple[Sequence[str], Sequence[str]]] = ()
) -> SuggestionRow | None:
    """The best unused group suggestion that is none of `exclude` (either side order)."""
    query = select(SuggestionRow).where(
        SuggestionRow.round_id == round_id, SuggestionRow.used.is_(False)
    )
    skip = {query_key(left, right) for left, right in exclude}
    if skip:
        query = query.where(SuggestionRow.key.not_in(skip))
    return s.scalars(query.order_by(SuggestionRow.rank).limit(1)).one_or_none()


def mark_suggestion_used(
    s: DbSession, round_id: int, left: Sequence[str], right: Sequence[str], source: str
) -> None:
    """Mark the suggestion a judgement answered as used.

    A suggestion with exactly the judgement's groups (either order) is used; a judgement
    from a suggestion that the user edited ("suggested", groups changed) uses the unused
    suggestion sharing the most behaviours with it.
    """
    unused = select(SuggestionRow).where(
        SuggestionRow.round_id == round_id, SuggestionRow.used.is_(False)
    )
    exact = s.scalars(
        unused.where(SuggestionRow.key == query_key(left, right))
        .order_by(SuggestionRow.rank)
        .limit(1)
    ).one_or_none()
    if exact is not None:
        exact.used = True
        return
    if source != "suggested":
        return
    members = {*left, *right}
    candidates = s.scalars(unused.order_by(SuggestionRow.rank).limit(EDITED_SCAN))
    overlap = [(len(members & {*row.left, *row.right}), -row.rank, row) for row in candidates]
    best = max(overlap, default=None, key=lambda t: (t[0], t[1]))
    if best is not None and best[0] > 0:
        best[2].used = True


def pairwise_next(s: DbSession, round_id: int, count: int = 2) -> list[PairQueueRow]:
    """The next `count` pairs of the round's queue that were neither judged nor skipped."""
    judged = {
        frozenset((left[0], right[0]))
        for left, right in s.execute(
            select(JudgementRow.left, JudgementRow.right).where(
                JudgementRow.round_id == round_id, JudgementRow.undone.is_(False)
            )
        ).all()
        if len(left) == 1 and len(right) == 1
    }
    out: list[PairQueueRow] = []
    for row in s.scalars(
        select(PairQueueRow)
        .where(PairQueueRow.round_id == round_id, PairQueueRow.skipped.is_(False))
        .order_by(PairQueueRow.position)
    ):
        if frozenset((row.a, row.b)) not in judged:
            out.append(row)
            if len(out) >= count:
                break
    return out


def skip_pair(s: DbSession, round_id: int, a: str, b: str) -> None:
    """Skip a pair of the round's queue (either order). Raises NotFoundError."""
    rows = list(
        s.scalars(
            select(PairQueueRow).where(
                PairQueueRow.round_id == round_id,
                ((PairQueueRow.a == a) & (PairQueueRow.b == b))
                | ((PairQueueRow.a == b) & (PairQueueRow.b == a)),
            )
        )
    )
    if not rows:
        raise NotFoundError(f"{a} and {b} are not a pair of this round's pairwise queue")
    for row in rows:
        row.skipped = True
