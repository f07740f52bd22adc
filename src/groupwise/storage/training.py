"""A session's learning curve: the points the worker writes as its agent trains (issue 24).

A continuous round gets a point after each refit of the reward model (its pairs and
validation accuracy) and after each evaluation of the greedy policy's true return
(`groupwise.worker.continuous`); every trained round, in either training mode, gets one
from its record's stats when its training is committed (`round_point`, from
`lifecycle.finish_training` and `finish_final`); and every round of an agent after the
first gets one when it opens, at its own pool's position (`opening_point`), so that the
page's "Pool sampled … ago" is of the round the person sees, not of the round before
(issue 39). Writing a point bumps the session's revision, so the event stream sends it
(``training``) at once.
"""

import math
from dataclasses import dataclass
from datetime import datetime

from sqlalchemy import select
from sqlalchemy.orm import Session as DbSession

from groupwise.storage.models import MAX_INTEGER, RoundRow, TrainingPointRow, utcnow
from groupwise.storage.sessions import get_session, touch


@dataclass(frozen=True)
class TrainingPoint:
    """What the agent had learned at one moment (`TrainingPointRow`'s fields)."""

    round: int
    at: datetime
    ppo_steps: int
    true_return: float | None
    """Mean true return of the greedy policy; None for a refit without evaluation."""
    pairs: int
    reward_val_accuracy: float | None
    pool_steps: int
    """PPO steps of the policy that sampled round `round`'s pool."""
    revision: int = 0


def finite(value: float | None) -> float | None:
    """`value`, or None for None, nan and inf (stored as null)."""
    return None if value is None or not math.isfinite(value) else float(value)


def add_point(
    s: DbSession,
    session_id: str,
    *,
    round_index: int,
    ppo_steps: int,
    true_return: float | None,
    pairs: int,
    reward_val_accuracy: float | None,
    pool_steps: int,
    now: datetime | None = None,
) -> TrainingPoint:
    """Store a point of round `round_index` and bump the session's revision. Raises
    NotFoundError."""
    session = get_session(s, session_id, lock=True)
    now = now or utcnow()
    touch(session, now)
    row = TrainingPointRow(
        session_id=session_id,
        round=round_index,
        at=now,
        ppo_steps=int(ppo_steps),
        true_return=finite(true_return),
        pairs=int(pairs),
        reward_val_accuracy=finite(reward_val_accuracy),
        pool_steps=int(pool_steps),
        revision=session.revision,
    )
    s.add(row)
    s.flush()
    return _point(row)


def opening_point(s: DbSession, session_id: str, round_index: int, ppo_steps: int) -> TrainingPoint:
    """Store the point of round `round_index` opening with a pool the policy at `ppo_steps`
    played: the fit of the newest point before it (none before the first), no evaluation.
    Raises NotFoundError."""
    newest = s.scalars(
        select(TrainingPointRow)
        .where(TrainingPointRow.session_id == session_id)
        .order_by(TrainingPointRow.revision.desc(), TrainingPointRow.id.desc())
        .limit(1)
    ).first()
    return add_point(
        s,
        session_id,
        round_index=round_index,
        ppo_steps=ppo_steps,
        true_return=None,
        pairs=0 if newest is None else newest.pairs,
        reward_val_accuracy=None if newest is None else newest.reward_val_accuracy,
        pool_steps=ppo_steps,
    )


def round_point(
    s: DbSession,
    session_id: str,
    round_index: int,
    stats: dict[str, object],
    now: datetime | None = None,
) -> TrainingPoint:
    """Store the point of round `round_index`'s committed training from its record's
    `stats` (`RoundRecord.stats`); its pool position is the stats' ``pool_steps`` when the
    worker put it there (the PPO steps of the policy that played the round's pool: a
    continuous round's is not the round before's), else the policy round `round_index` − 1
    left (its stats' ``env_steps``, 0 before the first round)."""
    before = s.scalar(
        select(RoundRow.stats).where(
            RoundRow.session_id == session_id, RoundRow.index == round_index - 1
        )
    )
    pool = stats.get("pool_steps", (before or {}).get("env_steps"))
    return add_point(
        s,
        session_id,
        round_index=round_index,
        ppo_steps=_int(stats.get("env_steps")),
        true_return=_float(stats.get("true_return_mean")),
        pairs=_int(stats.get("pairs_total")),
        reward_val_accuracy=_float(stats.get("reward_val_accuracy")),
        pool_steps=_int(pool),
        now=now,
    )


def _int(value: object) -> int:
    return int(value) if isinstance(value, int | float) else 0


def _float(value: object) -> float | None:
    return float(value) if isinstance(value, int | float) else None


def list_points(
    s: DbSession, session_id: str, after_revision: int | None = None
) -> list[TrainingPoint]:
    """The session's points in the order they were written; only those written after
    `after_revision` when given (the event stream's query). Raises NotFoundError."""
    get_session(s, session_id)
    query = select(TrainingPointRow).where(TrainingPointRow.session_id == session_id)
    if after_revision is not None:
        query = query.where(TrainingPointRow.revision > min(after_revision, MAX_INTEGER))
    rows = s.scalars(query.order_by(TrainingPointRow.revision, TrainingPointRow.id))
    return [_point(row) for row in rows]


def _point(row: TrainingPointRow) -> TrainingPoint:
    return TrainingPoint(
        round=row.round,
        at=row.at,
        ppo_steps=row.ppo_steps,
        true_return=row.true_return,
        pairs=row.pairs,
        reward_val_accuracy=row.reward_val_accuracy,
        pool_steps=row.pool_steps,
        revision=row.revision,
    )
