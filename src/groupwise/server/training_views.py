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
    """The newest round's newest point's fit and pool (a round's points carry its own
    pool's position; the ended round's record may come after the next round's opening
    point), the most PPO steps any point has, and the newest evaluated return: what the
    page shows (web/src/lib/training.ts, `trainingSummary`)."""
    if not points:
        return None
    newest_round = max(p.round for p in points)
    last = [p for p in points if p.round == newest_round][-1]
    steps = max(p.ppo_steps for p in points)
    evaluated = [p.true_return for p in points if p.true_return is not None]
    return TrainingSummary(
        round=newest_round,
        ppo_steps=steps,
        pairs=last.pairs,
        reward_val_accuracy=last.reward_val_accuracy,
        pool_age=max(0, steps - last.pool_steps),
        true_return=evaluated[-1] if evaluated else None,
    )


def training_curve(db: Database, session_id: str) -> TrainingCurve:
    """Every point of the session's curve and the summary. Raises NotFoundError."""
    with db.read() as s:
        # in time order: an evaluation's point is stored after the fact, as of its snapshot
        points = sorted(list_points(s, session_id), key=lambda p: (p.at, p.revision))
    return TrainingCurve(points=[point_out(p) for p in points], summary=summary(points))
