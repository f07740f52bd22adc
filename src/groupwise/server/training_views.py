"""The session's learning curve as the page reads it (`GET /api/sessions/{id}/training`,
the ``training`` event)."""

from collections.abc import Sequence

from groupwise.server.schemas.training import TrainingCurve, TrainingPointOut, TrainingSummary
from groupwise.storage import Database
from groupwise.storage.training import TrainingPoint, list_points


def point_out(point: TrainingPoint) -> TrainingPointOut:
    return TrainingPointOut(
        round=point.round,
        at=point.at,
        ppo_steps=point.ppo_steps,
        true_return=point.true_return,
        pairs=point.pairs,
        reward_val_accuracy=point.reward_val_accuracy,
        pool_steps=point.pool_steps,
    )


def summary(points: Sequence[TrainingPoint]) -> TrainingSummary | None:
    """The newest point's steps, fit and pool age, with the newest evaluated return."""
    if not points:
        return None
    last = points[-1]
    evaluated = [p.true_return for p in points if p.true_return is not None]
    return TrainingSummary(
        round=last.round,
        ppo_steps=last.ppo_steps,
        pairs=last.pairs,
        reward_val_accuracy=last.reward_val_accuracy,
        pool_age=last.pool_age,
        true_return=evaluated[-1] if evaluated else None,
    )


def training_curve(db: Database, session_id: str) -> TrainingCurve:
    """Every point of the session's curve and the summary. Raises NotFoundError."""
    with db.read() as s:
        # in time order: an evaluation's point is stored after the fact, as of its snapshot
        points = sorted(list_points(s, session_id), key=lambda p: (p.at, p.revision))
    return TrainingCurve(points=[point_out(p) for p in points], summary=summary(points))
