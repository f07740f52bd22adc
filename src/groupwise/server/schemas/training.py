"""The session's learning curve (`groupwise.storage.training`)."""

from datetime import datetime

from pydantic import Field

from groupwise.server.schemas.base import Out


class TrainingPointOut(Out):
    """A point of the session's learning curve (`groupwise.storage.training`)."""

    round: int = Field(description="the round the agent was training in (or after)")
    at: datetime = Field(description="when it was measured (UTC)")
    ppo_steps: int = Field(description="the agent's PPO env steps so far")
    true_return: float | None = Field(
        description="the greedy policy's mean true return; null for a refit without evaluation"
    )
    pairs: int = Field(description="preference pairs the reward model was last fitted on")
    reward_val_accuracy: float | None = Field(
        description="the last fit's held-out accuracy; null without a validation split"
    )
    pool_steps: int = Field(description="PPO env steps of the policy that sampled the pool")


class TrainingSummary(Out):
    """The newest point in words the page shows."""

    round: int
    ppo_steps: int = Field(description="PPO env steps so far")
    pairs: int = Field(description="pairs of the last refit")
    reward_val_accuracy: float | None = Field(description="the last refit's held-out accuracy")
    pool_age: int = Field(description="PPO env steps since the round's pool was sampled")
    true_return: float | None = Field(description="the newest evaluated true return")


class TrainingCurve(Out):
    """`GET /api/sessions/{id}/training`: the points in the order written, and the newest
    as a summary (null before the first)."""

    points: list[TrainingPointOut]
    summary: TrainingSummary | None
