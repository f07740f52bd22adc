"""The settings of an interactive session (docs/app.md, "Settings"), validated on creation.

A pydantic model (frozen, unknown fields rejected) because it is both the request schema of
`POST /api/sessions` and the JSON stored with the session. It is a whitelist of product
settings, each with a one-line help a person understands (the New-session page shows it):
`run_config` makes the core's `RunConfig` from them (written beside its checkpoints). The
core's other fields (the reward model, PPO beyond its preset, the research knobs) are not
settings of their own: a program or a test gives them as `research`, a partial `RunConfig`
merged over the session's (`RunConfig.merged`), and their meaning is in `groupwise.config`.
Sessions stored when the settings held the whole `PPOConfig` and `RewardConfig` (their
"ppo" and "reward" objects) load with those as their `research`.

A behaviour covers `clip_seconds` of simulated time (the env's default when null), played at
real speed (`groupwise.clips.timing`); a new session stores its L in steps (`for_env`), and
sessions stored before clips were measured in seconds keep the L = 30 steps they stored.

A session with a `dataset` labels a recorded dataset's episodes (issue 42,
docs/bring-your-own.md): it has no agent, so its agent settings are set to none whatever was
given (`NO_AGENT`: rounds-only, no PPO, pre-training, evaluation or pool variants).

The New-session page shows the fields its groups name first (`web/src/lib/settings-form.ts`)
and the others under "Advanced" (clips, the worker, shared sessions), `research` never.
"""

import dataclasses
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from groupwise.clips.timing import ClipTiming, default_clip_seconds, env_clip_timing
from groupwise.config import (
    ExplorationFraction,
    LoopConfig,
    PairCap,
    PairDerivation,
    PairOversample,
    RewardConfig,
    RunConfig,
    Seed,
    TrainingConfig,
)
from groupwise.preferences.judgement import MAX_GROUP
from groupwise.recipes import (
    DEFAULT_RECIPE,
    PPO_PRESETS,
    RECIPES,
    PPOPreset,
    RecipeName,
    RecipeParts,
    RewardInputs,
)

__all__ = [
    "HUMAN",
    "LIBRARY",
    "MAX_GROUP",
    "MAX_PPO_STEPS",
    "MAX_ROUNDS",
    "MIN_FRAGMENT_LENGTH",
    "SessionSettings",
]

MIN_FRAGMENT_LENGTH = 5
"""Fewest steps of a behaviour in the app."""
MAX_ROUNDS = 100
"""Most rounds of a session (round indices 0 … 99, rounds without feedback included)."""
MAX_PPO_STEPS = 10_000_000
"""Most PPO env steps of one training phase in the app."""
MAX_POOL_VARIANTS = 32
"""Most pool variants (`LoopConfig.pool_variants`) a session asks for."""
FINAL_STEPS_FACTOR = 2
"""The final phase trains this many rounds' worth of PPO steps unless `final_steps` says."""

NO_AGENT: dict[str, Any] = {
    "training": "rounds",
    "ppo_steps_per_round": 0,
    "final_steps": 0,
    "pretrain_steps": 0,
    "eval_episodes": 0,
    "pool_variants": 0,
}
"""The settings of a session without an agent (a recorded dataset's): set whatever is given."""

REMOVED_SETTINGS = frozenset({"stage_after_s"})
"""Settings of mechanisms removed since (the stager of continuous rounds, gone with fresh
pools, issue 39): stored sessions that carry them load without them."""

RECIPE_FIELDS: dict[str, str] = {
    "pretrain_steps": "pretrain_steps",
    "pool_variants": "pool_variants",
    "ppo_preset": "ppo",
    "reward_inputs": "reward_inputs",
    "exploration_fraction": "exploration_fraction",
    "teach_log_std": "teach_log_std",
}
"""The settings a recipe fills when left empty: setting → its `recipes.RecipeParts` field."""

LEGACY_SECTIONS = frozenset({"ppo", "reward"})
"""Settings stored before issue 38 held these core configs whole; they are `research` now."""

HUMAN = "human"
"""`LoopConfig.decision_maker` of a session a person answers (through the page)."""
LIBRARY = "library"
"""`SessionSettings.driver` of a session whose rounds a user's program publishes and trains
(`groupwise.worker.web_teacher.WebTeacher`); the app's worker leaves it alone."""


class SessionSettings(BaseModel):
    """What a session does each round; every number is a default, not a constant.

    `recipe` (`recipes.RECIPES`, default "teach") gives the parts `ppo_preset`,
    `pretrain_steps`, `pool_variants`, `reward_inputs`, `exploration_fraction` and
    `teach_log_std` left empty; `for_env` stores them resolved. A session stored before
    recipes has none (`stored`): it keeps the parts it stored."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    pool_size: int = Field(default=100, ge=8, le=1000, description="behaviours per round")
    pool_variants: int | None = Field(
        default=None,
        ge=0,
        le=MAX_POOL_VARIANTS,
        description="half of each pool comes from this many copies of the agent, each pushed "
        "one way, to show rarer behaviours",
    )
    fragment_length: int | None = Field(
        default=None,
        ge=MIN_FRAGMENT_LENGTH,
        le=1000,
        description="L, steps per behaviour (null: clip_seconds of simulated time)",
    )
    clip_seconds: float | None = Field(
        default=None,
        gt=0,
        le=20,
        description="simulated seconds a behaviour covers, played at real speed (null: the "
        "env's default; must agree with fragment_length)",
    )
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
        default=20_000, ge=0, le=MAX_PPO_STEPS, description="PPO env steps after each round"
    )
    rounds: int = Field(
        default=5,
        ge=1,
        le=MAX_ROUNDS,
        description="rounds of feedback in the session (the final phase follows the last)",
    )
    final_steps: int | None = Field(
        default=None,
        ge=0,
        le=MAX_PPO_STEPS,
        description="PPO env steps on the learned reward after the last round (null: "
        f"{FINAL_STEPS_FACTOR} × ppo_steps_per_round)",
    )
    suggestions: int = Field(
        default=100, ge=0, le=2000, description="pairwise suggestions precomputed per round"
    )
    seed: Seed = 0
    pair_derivation: PairDerivation = "cover"
    pair_cap: PairCap = None
    pair_oversample: PairOversample = 1.0
    training: Literal["rounds", "continuous"] = Field(
        default="continuous",
        description="continuous: the agent trains while you compare; rounds: it trains after "
        "each round ends",
    )
    recipe: RecipeName | None = Field(
        default=DEFAULT_RECIPE,
        description="how to teach: the recipe whose parts the empty PPO, pre-training and pool "
        "variant fields take",
        json_schema_extra={"x-choice-help": {r.name: r.summary() for r in RECIPES.values()}},
    )
    ppo_preset: PPOPreset | None = Field(
        default=None,
        description="PPO settings: study (small nets), mujoco (PPO's own) or "
        "mujoco-entropy (with an entropy bonus; null: the recipe's)",
    )
    pretrain_steps: int | None = Field(
        default=None,
        ge=0,
        le=MAX_PPO_STEPS,
        description="PPO steps the agent first explores, seeking new states, so the first "
        "behaviours differ more (null: the recipe's)",
    )
    reward_inputs: RewardInputs | None = Field(
        default=None,
        description="what the learned reward sees: obs (what a clip shows) or obs-act (the "
        "action too, a control cost; null: the recipe's)",
    )
    teach_log_std: float | None = Field(
        default=None,
        ge=-5.0,
        le=1.0,
        description="log σ of the action noise after pre-training; lower: clips closer to the "
        "agent you take away (null: the recipe's)",
    )
    # -- advanced knobs (the New-session page's "Advanced") ------------------------------
    driver: Literal["app", "library"] = Field(
        default="app",
        description="who prepares and trains the rounds: the app's worker, or a program "
        "using groupwise.WebTeacher",
    )
    frame_size: int = Field(
        default=240, ge=16, le=480, multiple_of=2, description="clip width and height in pixels"
    )
    render_workers: int = Field(
        default=2, ge=0, le=8, description="clip render processes (0: inline)"
    )
    lease_s: float = Field(
        default=60,
        ge=0,
        le=3600,
        description="a shared session: seconds a suggestion is offered to one annotator alone "
        "(0: everyone gets the same)",
    )
    overlap_share: float = Field(
        default=0.1,
        ge=0,
        le=1,
        description="a shared session: share of answered suggestions asked again of another "
        "annotator, to measure agreement",
    )
    exploration_fraction: ExplorationFraction | None = Field(
        default=None,
        description="share of a pool's sampled steps with random actions (null: the recipe's)",
    )
    eval_episodes: int = Field(
        default=5, ge=0, le=100, description="episodes measuring the true return after training"
    )
    dataset: str | None = Field(
        default=None,
        min_length=1,
        max_length=1000,
        description="a recorded dataset to label, no agent: minari:<id> (local store) or a "
        "Minari directory or .hdf5 path on the server",
    )
    """A minari:<id> is a dataset of the server's local Minari store (never downloaded); a path
    names a Minari dataset directory or a D4RL-style .hdf5 file (docs/bring-your-own.md)."""
    research: dict[str, Any] | None = Field(
        default=None,
        description="research settings: a partial run config merged over these "
        '(e.g. {"reward": {"ensemble_size": 5}}; groupwise.config)',
    )

    @model_validator(mode="before")
    @classmethod
    def _legacy_overrides(cls, data: Any) -> Any:
        """Sessions stored when the settings held the core's whole `PPOConfig` and
        `RewardConfig` ("ppo", "reward"; before that with None for "the default") read
        them as `research`."""
        if not isinstance(data, dict) or not data.keys() & LEGACY_SECTIONS:
            return data
        research = dict(data.get("research") or {})
        for key in LEGACY_SECTIONS & data.keys():
            if isinstance(data[key], dict):
                given = {k: v for k, v in data[key].items() if v is not None}
                research[key] = {**given, **research.get(key, {})}
            else:
                research[key] = data[key]  # validation names the bad value
        rest = {k: v for k, v in data.items() if k not in LEGACY_SECTIONS}
        return {**rest, "research": research}

    @model_validator(mode="before")
    @classmethod
    def _removed_dropped(cls, data: Any) -> Any:
        """Settings of mechanisms since removed (`REMOVED_SETTINGS`) are dropped: sessions
        stored with them still load."""
        if isinstance(data, dict) and data.keys() & REMOVED_SETTINGS:
            return {k: v for k, v in data.items() if k not in REMOVED_SETTINGS}
        return data

    @classmethod
    def stored(cls, data: Any) -> "SessionSettings":
        """Settings as a session stored them: one stored before recipes (no "recipe") has
        none, so it keeps the parts it stored (and the paper's for those it did not store,
        the defaults then); one stored before `reward_inputs` keeps the observation and the
        action its reward was built on, one without `exploration_fraction` the 0.25 then.
        One without `teach_log_std` takes the recipe's: it pre-trained before that part
        existed (its pre-trained policy is kept, `worker.job`), unless it never opened.

        Raises:
            pydantic.ValidationError: a field fails validation.
        """
        if isinstance(data, dict) and "recipe" not in data:
            data = {**data, "recipe": None}
        if isinstance(data, dict) and "reward_inputs" not in data:
            data = {**data, "reward_inputs": "obs-act"}
        if isinstance(data, dict) and data.get("exploration_fraction") is None:
            data = {**data, "exploration_fraction": 0.25}
        return cls.model_validate(data)

    def recipe_parts(self, env: str) -> RecipeParts:
        """The pre-training, its action noise after, pool variants, PPO preset, reward inputs
        and random actions of a session on `env`: each set here, else the recipe's
        (`recipes.RECIPES`; none: the paper's, the defaults before recipes)."""
        given = {part: getattr(self, name) for name, part in RECIPE_FIELDS.items()}
        parts = RECIPES[self.recipe or "paper"].parts(env)
        return dataclasses.replace(parts, **{k: v for k, v in given.items() if v is not None})

    @model_validator(mode="before")
    @classmethod
    def _no_agent_for_a_dataset(cls, data: Any) -> Any:
        """A dataset session's agent settings are `NO_AGENT`'s, whatever was given."""
        if isinstance(data, dict) and data.get("dataset"):
            return {**data, **NO_AGENT}
        return data

    @property
    def has_agent(self) -> bool:
        """Whether the session trains an agent (False: it labels a recorded `dataset`)."""
        return self.dataset is None

    @model_validator(mode="after")
    def _research_is_a_config(self) -> "SessionSettings":
        if not self.research:
            return self
        try:
            RunConfig().merged(self.research)
        except ValidationError as error:  # one sentence naming each field under research
            parts = [
                f"research.{'.'.join(map(str, e['loc']))}: {e['msg'].removeprefix('Value error, ')}"
                for e in error.errors()
            ]
            raise ValueError("; ".join(parts)) from None
        return self

    def clip_timing(self, env: str) -> ClipTiming:
        """L and how a clip of `env` plays it (`clips.timing`): `fragment_length` steps if
        set, else `clip_seconds` (default: the env's) of simulated time.

        Raises:
            ValueError: unknown env.
        """
        return env_clip_timing(env, self.clip_seconds, steps=self.fragment_length)

    @property
    def final_ppo_steps(self) -> int:
        """PPO steps of the final phase: `final_steps`, or `FINAL_STEPS_FACTOR` rounds'
        worth (sessions stored before the final phase existed have none set)."""
        if self.final_steps is not None:
            return self.final_steps
        return min(MAX_PPO_STEPS, FINAL_STEPS_FACTOR * self.ppo_steps_per_round)

    def for_env(self, env: str) -> "SessionSettings":
        """These settings with `fragment_length` fixed for `env` (and `clip_seconds` the
        duration asked for, when L was not given in steps), `final_steps` and the recipe's
        parts resolved (`recipe_parts`): what a new session stores, so that its L and its
        recipe's parts never change, whatever later versions choose as the env's default.

        Raises:
            ValueError: unknown env; both set and disagreeing; or a clip under
                `MIN_FRAGMENT_LENGTH` steps.
        """
        if self.final_steps is None:
            return self.model_copy(update={"final_steps": self.final_ppo_steps}).for_env(env)
        parts = self.recipe_parts(env)
        resolved = {
            name: getattr(parts, part)
            for name, part in RECIPE_FIELDS.items()
            if getattr(self, name) is None and getattr(parts, part) is not None
        }  # a part the recipe leaves empty (the paper's action noise) stays empty
        if resolved:
            return self.model_copy(update=resolved).for_env(env)
        timing = self.clip_timing(env)
        if self.fragment_length is None:
            seconds = self.clip_seconds or default_clip_seconds(env)
            return self.model_copy(
                update={"fragment_length": timing.steps, "clip_seconds": seconds}
            )._checked(env)
        if self.clip_seconds is not None:
            asked = env_clip_timing(env, self.clip_seconds).steps
            if asked != self.fragment_length:
                raise ValueError(
                    f"fragment_length {self.fragment_length} and clip_seconds "
                    f"{self.clip_seconds} ({asked} steps of {env}) disagree: give one of them"
                )
        return self._checked(env)

    def _checked(self, env: str) -> "SessionSettings":
        steps = self.clip_timing(env).steps
        if steps < MIN_FRAGMENT_LENGTH:
            raise ValueError(
                f"clip_seconds {self.clip_seconds} is {steps} steps of {env}; a behaviour "
                f"needs at least {MIN_FRAGMENT_LENGTH}"
            )
        return self

    def run_config(self, env: str) -> RunConfig:
        """The session as the core's configuration; its feedback comes from a person."""
        parts = self.recipe_parts(env)
        loop = LoopConfig(
            env=env,
            decision_maker=HUMAN,
            comparisons=max(1, self.comparisons_per_round * self.rounds),
            rounds=self.rounds,
            steps=self.ppo_steps_per_round * self.rounds,
            final_steps=self.final_ppo_steps,
            fragment_length=self.clip_timing(env).steps,
            exploration_fraction=parts.exploration_fraction,
            pool_cap=max(2, self.pool_size),
            eval_episodes=self.eval_episodes,
            pair_derivation=self.pair_derivation,
            pair_cap=self.pair_cap,
            pair_oversample=self.pair_oversample,
            pool_size=self.pool_size,
            pool_variants=parts.pool_variants,
            seed=self.seed,
        )
        training = TrainingConfig(
            mode=self.training,
            pretrain_steps=parts.pretrain_steps,
            teach_log_std=parts.teach_log_std,
        )
        reward = RewardConfig(use_actions=parts.reward_inputs == "obs-act")
        cfg = RunConfig(loop=loop, ppo=PPO_PRESETS[parts.ppo], training=training, reward=reward)
        return cfg.merged(self.research) if self.research else cfg
