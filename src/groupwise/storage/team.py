"""Who did what in a shared session (docs/teams.md): per annotator, their comparisons,
pairs and time shown, their agreement with the other annotators, and with the reward model.

- comparisons and pairs: their judgements that were not undone, and those judgements'
  pairs, over all rounds;
- time shown: per round they showed in a page (`annotators.record_view`), from their first
  showing until the round closed (or now, while it is open); the owner also gets the rounds
  that were shown before views were recorded per annotator;
- agreement: their labels against the others' on the same preference pairs (a round's
  unordered pair of behaviours; a person's latest label counts), Cohen's κ and the share
  of agreeing labels with the count n they rest on (`groupwise.preferences.agreement`).
  A judgement of group L against group R labels every pair of L × R: the pairs it trains
  on are a max(m, n) sample of them, drawn from the judgement's own stream, so two people
  answering the same groups would otherwise rarely share one;
- model agreement: their strict preferences against the reward model's predicted returns
  that the round's pool stores (``predictions.npz``, the ensemble that chose the pool,
  trained on the rounds before it): round 0's untrained model is left out, as are rounds
  whose pool is gone.
"""

from collections import defaultdict
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path

import numpy as np
from sqlalchemy import func, select
from sqlalchemy.orm import Session as DbSession

from groupwise.episodes.ids import behaviour_id
from groupwise.preferences.agreement import (
    Agreement,
    ModelAgreement,
    model_agreement,
    oriented,
    rater_agreement,
)
from groupwise.preferences.judgement import EQUAL, LEFT_BETTER, RIGHT_BETTER
from groupwise.storage.annotators import OWNER, list_annotators, owner_name
from groupwise.storage.models import (
    JudgementRow,
    PairRow,
    RoundRow,
    RoundViewRow,
    SessionRow,
    utcnow,
)

PREDICTIONS_FILE = "predictions.npz"
"""The pool file holding the predicted returns of the ensemble that chose the pool
(`groupwise.pool.files`)."""

ScoreSource = Callable[[str, int, str | None], Mapping[str, float] | None]
"""(session id, round index, the round's pool directory) → behaviour name → the reward
model's predicted return, or None when there is none (`pool_scores`)."""

LABELS = {"left": LEFT_BETTER, "right": RIGHT_BETTER, "equal": EQUAL}
"""A judgement's label → P(a left behaviour preferred to a right one)."""

PairKey = tuple[int, str, str]
"""A round and an oriented pair of its behaviours."""


@dataclass(frozen=True)
class AnnotatorStats:
    """One person's share of a session's work and how well it agrees."""

    id: str
    """ "owner" or the annotator's id."""
    name: str
    comparisons: int
    pairs: int
    shown_s: float
    agreement: Agreement
    model_agreement: ModelAgreement
    removed: bool = False


def pool_scores(data_dir: Path, pool_dir: str | None) -> dict[str, float] | None:
    """Behaviour name → the mean predicted return of the ensemble that chose the pool in
    `pool_dir` (relative to `data_dir`; only inside it), or None without predictions."""
    if pool_dir is None:
        return None
    root = data_dir.resolve()
    path = (root / pool_dir / PREDICTIONS_FILE).resolve()
    if not path.is_relative_to(root) or not path.is_file():
        return None
    try:
        with np.load(path) as data:
            predicted = np.asarray(data["predicted_returns"], dtype=float)
    except (OSError, KeyError, ValueError):
        return None
    if predicted.ndim != 2 or predicted.shape[1] == 0:
        return None
    return {behaviour_id(i): float(v) for i, v in enumerate(predicted.mean(axis=1))}


def team_stats(
    s: DbSession,
    session: SessionRow,
    now: datetime | None = None,
    scores: ScoreSource | None = None,
    *,
    include_removed: bool = False,
) -> list[AnnotatorStats]:
    """The owner's and each annotator's numbers (module docstring), the owner first, then
    the annotators in the order they were added (removed ones only with
    `include_removed`, and then only those with judgements)."""
    now = now or utcnow()
    people = [(OWNER, owner_name(session), False)] + [
        (a.id, a.name, a.removed)
        for a in list_annotators(s, session.id, include_removed=include_removed)
    ]
    live = (JudgementRow.session_id == session.id, JudgementRow.undone.is_(False))
    comparisons = {
        key or OWNER: int(n)
        for key, n in s.execute(
            select(JudgementRow.annotator_id, func.count(JudgementRow.id))
            .where(*live)
            .group_by(JudgementRow.annotator_id)
        ).all()
    }
    pair_counts = {
        key or OWNER: int(n)
        for key, n in s.execute(
            select(JudgementRow.annotator_id, func.count(PairRow.id))
            .join(PairRow, PairRow.judgement_id == JudgementRow.id)
            .where(*live)
            .group_by(JudgementRow.annotator_id)
        ).all()
    }
    labels: dict[str, dict[PairKey, float]] = defaultdict(dict)
    for who, round_index, left, right, label in s.execute(
        select(
            JudgementRow.annotator_id,
            JudgementRow.round_index,
            JudgementRow.left,
            JudgementRow.right,
            JudgementRow.label,
        )
        .where(*live)
        .order_by(JudgementRow.seq)
    ).all():
        mine = labels[who or OWNER]
        for a in left:
            for b in right:  # the judgement's label holds for every pair of L × R
                (lo, hi), oriented_label = oriented(a, b, LABELS[label])
                mine[(round_index, lo, hi)] = oriented_label  # the latest label counts
    margins = _margins(s, session.id, labels, scores)
    shown = _shown_seconds(s, session.id, now)
    stats = []
    for key, name, removed in people:
        if removed and key not in comparisons:
            continue
        mine = labels.get(key, {})
        others = [theirs for other, theirs in labels.items() if other != key]
        stats.append(
            AnnotatorStats(
                id=key,
                name=name,
                comparisons=comparisons.get(key, 0),
                pairs=pair_counts.get(key, 0),
                shown_s=round(shown.get(key, 0.0), 3),
                agreement=rater_agreement(mine, others),
                model_agreement=model_agreement(mine, margins),
                removed=removed,
            )
        )
    return stats


def _margins(
    s: DbSession,
    session_id: str,
    labels: Mapping[str, Mapping[PairKey, float]],
    scores: ScoreSource | None,
) -> dict[PairKey, float]:
    """Predicted return of the pair's first behaviour minus its second's, for every
    labelled pair of a round after round 0 whose pool has predictions."""
    if scores is None:
        return {}
    wanted = {key[0] for by_person in labels.values() for key in by_person if key[0] > 0}
    if not wanted:
        return {}
    pools = dict(
        s.execute(
            select(RoundRow.index, RoundRow.pool_dir).where(
                RoundRow.session_id == session_id, RoundRow.index.in_(wanted)
            )
        ).all()
    )
    by_round = {r: scores(session_id, r, pools.get(r)) for r in wanted}
    margins: dict[PairKey, float] = {}
    for by_person in labels.values():
        for key in by_person:
            predicted = by_round.get(key[0])
            if predicted is not None and key[1] in predicted and key[2] in predicted:
                margins[key] = predicted[key[1]] - predicted[key[2]]
    return margins


def _shown_seconds(s: DbSession, session_id: str, now: datetime) -> dict[str, float]:
    """Per person, the seconds from their first showing of each round to its close."""
    rounds = {
        row.id: row for row in s.scalars(select(RoundRow).where(RoundRow.session_id == session_id))
    }
    views = s.execute(
        select(RoundViewRow.round_id, RoundViewRow.annotator, RoundViewRow.shown_at).where(
            RoundViewRow.round_id.in_(rounds)
        )
    ).all()
    viewed = {round_id for round_id, _, _ in views}
    # rounds shown before views were recorded per person: the owner's (the one person then)
    legacy = [
        (row.id, OWNER, row.shown_at)
        for row in rounds.values()
        if row.shown_at is not None and row.id not in viewed
    ]
    seconds: dict[str, float] = defaultdict(float)
    for round_id, who, shown_at in [*views, *legacy]:
        closed = rounds[round_id].closed_at or now
        seconds[who] += max(0.0, (closed - shown_at).total_seconds())
    return seconds
