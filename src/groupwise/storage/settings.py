"""The settings of an interactive session (docs/app.md, "Settings"), validated on creation.

A pydantic model (frozen, unknown fields rejected) because it is both the request schema of
`POST /api/sessions` and the JSON stored with the session. It is a view of the core's one
config (`groupwise.config`), not a mirror: PPO and the reward model are the core's own
`PPOConfig` and `RewardConfig`, the loop's fields reuse the core's field types, and
`run_config` is the session as a `RunConfig` (written beside its checkpoints). What only the
app has (per-round budgets, the round timer, suggestions, clip size) lives here alone.

The fields after `seed` are advanced knobs that the page does not show; tests and the
latency benchmark use them to make rounds take seconds.
"""

from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from groupwise.config import (
    ExplorationFraction,
    LoopConfig,
    PairCap,
    PairDerivation,
    PPOConfig,
    RewardConfig,
    RunConfig,
    Seed,
)
from groupwise.preferences.judgement import MAX_GROUP

__all__ = ["HUMAN", "LIBRARY", "MAX_GROUP", "SessionSettings"]

HUMAN = "human"
"""`LoopConfig.oracle` of a session a person answers (through the page)."""
LIBRARY = "library"
"""`SessionSettings.driver` of a session whose rounds a user's program publishes and trains
(`groupwise.server.web_teacher.WebTeacher`); the app's worker leaves it alone."""


class SessionSettings(BaseModel):
    """What a session does each round; every number is a default, not a constant."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    pool_size: int = Field(default=100, ge=8, le=200, description="behaviours per round")
    fragment_length: Annotated[int, Field(ge=5, le=200, description="L, steps per behaviour")] = 30
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
    seed: Seed = 0
    pair_derivation: PairDerivation = "cover"
    pair_cap: PairCap = None
    # -- advanced knobs (not shown by the page) -------------------------------------------
    driver: Literal["app", "library"] = Field(
        default="app",
        description="who prepares and trains the rounds: the app's worker, or a program "
        "using groupwise.WebTeacher",
    )
    frame_size: int = Field(
        default=240, ge=16, le=480, multiple_of=2, description="clip width, height"
    )
    render_workers: int = Field(
        default=2, ge=0, le=8, description="clip render processes (0: inline)"
    )
    exploration_fraction: ExplorationFraction = 0.25
    eval_episodes: int = Field(
        default=5, ge=0, le=100, description="episodes measuring the true return after training"
    )
    ppo: PPOConfig = Field(default_factory=PPOConfig, description="PPO (SPEC §3)")
    reward: RewardConfig = Field(default_factory=RewardConfig, description="reward model")

    @model_validator(mode="before")
    @classmethod
    def _legacy_overrides(cls, data: Any) -> Any:
        """Sessions stored before the settings took the core's models kept PPO and reward
        overrides with None for "the default": drop those Nones."""
        if isinstance(data, dict):
            for key in ("ppo", "reward"):
                if isinstance(data.get(key), dict):
                    data = {**data, key: {k: v for k, v in data[key].items() if v is not None}}
        return data

    def run_config(self, env: str) -> RunConfig:
        """The session as the core's configuration; its feedback comes from a person."""
        loop = LoopConfig(
            env=env,
            oracle=HUMAN,
            comparisons=max(1, self.comparisons_per_round * self.rounds),
            rounds=self.rounds,
            steps=self.ppo_steps_per_round * self.rounds,
            fragment_length=self.fragment_length,
            exploration_fraction=self.exploration_fraction,
            pool_cap=max(2, self.pool_size),
            eval_episodes=self.eval_episodes,
            pair_derivation=self.pair_derivation,
            pair_cap=self.pair_cap,
            seed=self.seed,
        )
        return RunConfig(loop=loop, reward=self.reward, ppo=self.ppo)
