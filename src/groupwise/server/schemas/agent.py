"""The finished session's agent: what the download holds, its rounds and video, picking its
round, and more training."""

from typing import Literal

from pydantic import Field, model_validator

from groupwise.server.schemas.base import In, Out
from groupwise.storage.settings import MAX_PPO_STEPS, MAX_ROUNDS


class ContinueIn(In):
    """More training for a finished session: PPO steps on the frozen reward, or rounds."""

    steps: int | None = Field(
        default=None, ge=1, le=MAX_PPO_STEPS, description="PPO env steps on the frozen reward"
    )
    rounds: int | None = Field(
        default=None, ge=1, le=MAX_ROUNDS, description="more feedback rounds"
    )

    @model_validator(mode="after")
    def _one_of(self) -> "ContinueIn":
        if (self.steps is None) == (self.rounds is None):
            raise ValueError("give either steps or rounds")
        return self


class AgentRound(Out):
    """One round of the session, as the finished page's chart shows it."""

    round: int
    feedback: bool = Field(description="false: PPO on the frozen learned reward only")
    judgements: int
    pairs_total: int
    env_steps: int
    true_return_mean: float | None = Field(description="null: not evaluated")
    true_return_std: float | None
    target_score_mean: float | None = Field(
        description="a target env's episode score after the round, in the target's unit; "
        "null for other envs, rounds not evaluated and agents published before it was recorded"
    )
    target_score_std: float | None
    video: bool = Field(
        default=False,
        description="the round's greedy policy was filmed (GET …/agent/rounds/{round}.mp4)",
    )
    checkpoint: bool = Field(
        default=False,
        description="the round's checkpoint is there: the person may pick it as take-away agent",
    )


class AgentVideo(Out):
    """The final agent's video (GET …/agent.mp4): one greedy episode, at real speed."""

    seconds: float
    fps: float
    frames: int
    width: int
    height: int
    episode_return: float = Field(
        description="the filmed episode's true return (a target env: its per-step score sum)"
    )
    target_score: float | None = Field(
        description="a target env's score of the filmed episode, in its unit"
    )


class AgentTarget(Out):
    """The target a finished session's env scores: its units and levels (`GET /api/envs` has
    its definition)."""

    name: str = Field(examples=["hopper-backflip"])
    unit: str = Field(description="what an episode's score counts", examples=["backward turns"])
    step_unit: str = Field(
        description="the unit of a per-step score and of their sum (true_return_mean)",
        examples=["rad/s"],
    )
    threshold: float = Field(description="an episode succeeds when its score reaches this")
    stretch: float = Field(description="the more ambitious level")


ChosenBy = Literal["last", "teacher", "person"]
"""Who chose the take-away agent's round (`AgentOut.chosen_by`)."""


class AgentOut(Out):
    """The finished session's agent: what the download holds and how it came about."""

    env: str
    round: int = Field(description="the round whose checkpoint the agent is")
    env_steps: int
    measure: str = Field(
        description='what true_return_mean measures: "true return", or in a target env the '
        'sum of its per-step scores, "per-step score sum (rad/s)"'
    )
    true_return_mean: float | None
    true_return_std: float | None
    target: AgentTarget | None = Field(description="null: not a target env")
    target_score_mean: float | None = Field(
        description="a target env's episode score after the last round, in target.unit (mean "
        "over the evaluation episodes): whether teaching worked"
    )
    target_score_std: float | None
    video: AgentVideo | None
    rounds: list[AgentRound]
    chosen_by: ChosenBy = Field(
        default="last",
        description='who chose `round`: "last" (nobody: the last round, the default), "teacher" '
        '(a simulated teacher, headless) or "person" (PUT …/agent/round)',
    )


class AgentPickIn(In):
    """The round whose policy the session hands over (its agent.zip and agent.json)."""

    round: int = Field(ge=0, description="a round of the session with a checkpoint")
