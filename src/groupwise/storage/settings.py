"""The settings of an interactive session (docs/app.md, "Settings"), validated on creation.

A pydantic model (frozen, unknown fields rejected) because it is both the request schema of
`POST /api/sessions` and the JSON stored with the session; the worker turns it into the
core's configs (`groupwise.config`, `groupwise.prepare.PoolConfig`).

The fields after `seed` are advanced knobs that the page does not show; tests and the
latency benchmark use them to make rounds take seconds.
"""

from typing import Annotated, Self

from pydantic import BaseModel, ConfigDict, Field, model_validator

MAX_GROUP = 8
"""Largest group in a groupwise comparison (paper §6: 8 keeps comparisons humanly possible)."""


class PPOSettings(BaseModel):
    """Overrides of `groupwise.config.PPOConfig` (None keeps the study's default)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    n_envs: int | None = Field(default=None, ge=1, le=64, description="parallel envs")
    n_steps: int | None = Field(
        default=None, ge=8, le=8192, description="steps per env per rollout"
    )
    batch_size: int | None = Field(default=None, ge=2, le=65536, description="minibatch size")
    n_epochs: int | None = Field(default=None, ge=1, le=50, description="epochs per rollout")
    learning_rate: float | None = Field(default=None, gt=0, le=1, description="Adam step size")
    net_arch: Annotated[list[Annotated[int, Field(ge=1, le=1024)]], Field(max_length=4)] | None = (
        Field(
            default=None, min_length=1, description="hidden layer widths of policy and value nets"
        )
    )


class RewardSettings(BaseModel):
    """Overrides of `groupwise.config.RewardConfig` (None keeps the default)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    ensemble_size: int | None = Field(default=None, ge=2, le=10, description="K ensemble members")
    epochs: int | None = Field(
        default=None, ge=1, le=100, description="epochs per fit after round 0"
    )
    initial_epoch_multiplier: float | None = Field(
        default=None, ge=1, le=100, description="round 0 trains this many times more epochs"
    )


class SessionSettings(BaseModel):
    """What a session does each round; every number is a default, not a constant."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    pool_size: int = Field(default=100, ge=8, le=200, description="behaviours per round")
    fragment_length: int = Field(default=30, ge=5, le=200, description="L, steps per behaviour")
    round_seconds: float = Field(
        default=600, ge=0, le=86_400, description="round time budget in seconds (0 = no limit)"
    )
    comparisons_per_round: int = Field(
        default=20,
        ge=0,
        le=10_000,
        description="round ends after this many judgements (0 = no limit)",
    )
    ppo_steps_per_round: int = Field(
        default=20_000, ge=0, le=10_000_000, description="PPO env steps after each round"
    )
    rounds: int = Field(default=5, ge=1, le=100, description="rounds in the session")
    suggestions: int = Field(
        default=100, ge=0, le=2000, description="top-k pairwise suggestion edges precomputed"
    )
    seed: int = Field(
        default=0, ge=0, le=2**31 - 1, description="everything random derives from it"
    )
    # -- advanced knobs (not shown by the page) -------------------------------------------
    frame_size: int = Field(
        default=240, ge=16, le=480, multiple_of=2, description="clip width, height"
    )
    render_workers: int = Field(
        default=2, ge=0, le=8, description="clip render processes (0: inline)"
    )
    exploration_fraction: float = Field(
        default=0.25,
        ge=0,
        lt=1,
        description="share of sampled steps with random actions (SPEC §3.1)",
    )
    eval_episodes: int = Field(
        default=5, ge=0, le=100, description="episodes measuring the true return after training"
    )
    ppo: PPOSettings = Field(default=PPOSettings(), description="PPO overrides")
    reward: RewardSettings = Field(default=RewardSettings(), description="reward overrides")

    @model_validator(mode="after")
    def _consistent(self) -> Self:
        from groupwise.config import PPOConfig

        defaults = PPOConfig()
        n_envs = self.ppo.n_envs or defaults.n_envs
        n_steps = self.ppo.n_steps or defaults.n_steps
        batch = self.ppo.batch_size or defaults.batch_size
        if batch > n_envs * n_steps:
            raise ValueError(
                f"ppo.batch_size {batch} is larger than a rollout (n_envs × n_steps = "
                f"{n_envs * n_steps})"
            )
        return self
