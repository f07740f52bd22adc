"""A round's pool in the database: behaviours, group suggestions, edges, the pairwise queue.

The worker computes a round (`groupwise.worker.jobs`) and stores it in one transaction with
`store_prepared_round`, which also opens the round; everything else here reads it.

Several people on one session (docs/teams.md): a suggestion or a pair of the pairwise queue
offered to one of them is *leased* to them (`holder`: "owner" or an annotator id) for
`lease_s` seconds, and nobody else is offered it meanwhile. A share of the answered
suggestions (`overlap_share`, chosen by `chosen_for_overlap` from the session's seed) waits
for a second annotator's answer before it counts as used, so their agreement can be
measured.
"""

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from datetime import datetime, timedelta

import numpy as np
from sqlalchemy import delete, or_, select, update
from sqlalchemy.orm import Session as DbSession

from groupwise.episodes.ids import behaviour_id
from groupwise.storage.errors import NotFoundError
from groupwise.storage.lifecycle import open_round
from groupwise.storage.models import (
    BehaviourRow,
    JudgementRow,
    PairQueueRow,
    RoundRow,
    SuggestionEdgeRow,
    SuggestionRow,
    utcnow,
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


OWNER = "owner"
"""The session owner's key where leases and answers record who (`storage.annotators`)."""
OVERLAP_STREAM = 2
"""Tag of the random stream that picks the suggestions asked twice (`chosen_for_overlap`;
a judgement's pairs use tag 1, `groupwise.run.streams`)."""


def next_suggestion(
    s: DbSession,
    round_id: int,
    exclude: Sequence[tuple[Sequence[str], Sequence[str]]] = (),
    *,
    holder: str = OWNER,
    lease_s: float = 0.0,
    now: datetime | None = None,
) -> SuggestionRow | None:
    """The best unused group suggestion for `holder` that is none of `exclude` (either side
    order), not leased to someone else, and not one `holder` answered first. With
    `lease_s` > 0 it is leased to `holder` until `lease_s` seconds from `now`, and
    `holder`'s leases of the excluded suggestions end (a write: call it in a write
    transaction)."""
    now = now or utcnow()
    query = select(SuggestionRow).where(
        SuggestionRow.round_id == round_id,
        SuggestionRow.used.is_(False),
        or_(SuggestionRow.first_by.is_(None), SuggestionRow.first_by != holder),
    )
    skip = {query_key(left, right) for left, right in exclude}
    if skip:
        query = query.where(SuggestionRow.key.not_in(skip))
    if lease_s > 0:
        query = query.where(
            or_(
                SuggestionRow.leased_to.is_(None),
                SuggestionRow.leased_to == holder,
                SuggestionRow.lease_until <= now,
            )
        )
    found = s.scalars(query.order_by(SuggestionRow.rank).limit(1)).one_or_none()
    if lease_s > 0:
        if skip:
            s.execute(
                update(SuggestionRow)
                .where(
                    SuggestionRow.round_id == round_id,
                    SuggestionRow.leased_to == holder,
                    SuggestionRow.key.in_(skip),
                )
                .values(leased_to=None, lease_until=None)
            )
        if found is not None:
            found.leased_to = holder
            found.lease_until = now + timedelta(seconds=lease_s)
        s.flush()
    return found


def chosen_for_overlap(seed: int, round_index: int, rank: int, share: float) -> bool:
    """Whether suggestion `rank` of round `round_index` is asked of a second annotator:
    a draw of its own stream, ``SeedSequence([seed, round, OVERLAP_STREAM, rank])``, below
    `share` (so the same suggestions are chosen whoever answers first)."""
    if share <= 0:
        return False
    rng = np.random.default_rng(np.random.SeedSequence([seed, round_index, OVERLAP_STREAM, rank]))
    return bool(rng.random() < share)


@dataclass(frozen=True)
class Overlap:
    """How a session asks suggestions twice: `share` of them (0: never), picked from
    `seed`'s stream of round `round_index`."""

    share: float
    seed: int
    round_index: int


def mark_suggestion_used(
    s: DbSession,
    round_id: int,
    left: Sequence[str],
    right: Sequence[str],
    source: str,
    *,
    holder: str = OWNER,
    overlap: Overlap | None = None,
) -> int | None:
    """Mark the suggestion a judgement of `holder` answered as used; its id (None: none).

    A suggestion with exactly the judgement's groups (either order) is answered; a
    judgement from a suggestion that the user edited ("suggested", groups changed) answers
    the unused suggestion sharing the most behaviours with it. A suggestion `holder`
    answered first is not answered again by them. An answered suggestion is used, unless
    it is the first answer and `overlap` chooses it (`chosen_for_overlap`): then it waits,
    unleased, for another annotator's.
    """
    unused = select(SuggestionRow).where(
        SuggestionRow.round_id == round_id,
        SuggestionRow.used.is_(False),
        or_(SuggestionRow.first_by.is_(None), SuggestionRow.first_by != holder),
    )
    answered = s.scalars(
        unused.where(SuggestionRow.key == query_key(left, right))
        .order_by(SuggestionRow.rank)
        .limit(1)
    ).one_or_none()
    if answered is None and source == "suggested":
        members = {*left, *right}
        candidates = s.scalars(unused.order_by(SuggestionRow.rank).limit(EDITED_SCAN))
        overlaps = [(len(members & {*row.left, *row.right}), -row.rank, row) for row in candidates]
        best = max(overlaps, default=None, key=lambda t: (t[0], t[1]))
        if best is not None and best[0] > 0:
            answered = best[2]
    if answered is None:
        return None
    first = answered.first_by is None
    if (
        first
        and overlap is not None
        and chosen_for_overlap(overlap.seed, overlap.round_index, answered.rank, overlap.share)
    ):
        answered.first_by = holder
    else:
        answered.used = True
    answered.leased_to = None
    answered.lease_until = None
    return answered.id


def pairwise_next(
    s: DbSession,
    round_id: int,
    count: int = 2,
    *,
    holder: str = OWNER,
    lease_s: float = 0.0,
    now: datetime | None = None,
) -> list[PairQueueRow]:
    """The next `count` pairs of the round's queue that were neither judged nor skipped,
    nor leased to someone other than `holder`. With `lease_s` > 0 the first is leased to
    `holder` for `lease_s` seconds from `now` (a write: call it in a write transaction)."""
    now = now or utcnow()
    judged = {
        frozenset((left[0], right[0]))
        for left, right in s.execute(
            select(JudgementRow.left, JudgementRow.right).where(
                JudgementRow.round_id == round_id, JudgementRow.undone.is_(False)
            )
        ).all()
        if len(left) == 1 and len(right) == 1
    }
    query = select(PairQueueRow).where(
        PairQueueRow.round_id == round_id, PairQueueRow.skipped.is_(False)
    )
    if lease_s > 0:
        query = query.where(
            or_(
                PairQueueRow.leased_to.is_(None),
                PairQueueRow.leased_to == holder,
                PairQueueRow.lease_until <= now,
            )
        )
    out: list[PairQueueRow] = []
    for row in s.scalars(query.order_by(PairQueueRow.position)):
        if frozenset((row.a, row.b)) not in judged:
            out.append(row)
            if len(out) >= count:
                break
    if lease_s > 0 and out:
        out[0].leased_to = holder
        out[0].lease_until = now + timedelta(seconds=lease_s)
        s.flush()
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
