"""How many comparisons and pairs a session holds, this round and in total (undone ones
not counted): the numbers the page shows beside the round."""

from dataclasses import dataclass

from sqlalchemy import func, select
from sqlalchemy.orm import Session as DbSession

from groupwise.storage.models import JudgementRow, PairRow, SessionRow


@dataclass(frozen=True)
class Counts:
    """Non-undone judgements and their pairs, in the current round and in total."""

    comparisons_round: int
    pairs_round: int
    comparisons_total: int
    pairs_total: int


def counts(s: DbSession, session: SessionRow) -> Counts:
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
