"""Request and response schemas: the contract with the web UI (docs/app.md).

FastAPI publishes them as the OpenAPI schema at ``/api/openapi.json``, from which the web
UI's types are generated. Requests reject unknown fields; every string and list is bounded.
"""

from datetime import datetime
from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from groupwise.episodes.ids import BEHAVIOUR_PREFIX, behaviour_id
from groupwise.storage.settings import MAX_GROUP, MAX_PPO_STEPS, MAX_ROUNDS, SessionSettings

Phase = Literal["preparing", "ready", "training", "finishing", "finished", "failed"]
Mode = Literal["groupwise", "pairwise"]
Label = Literal["left", "right", "equal"]
Source = Literal["suggested", "explored", "pairwise"]
BehaviourId = Annotated[
    str,
    Field(pattern=rf"^{BEHAVIOUR_PREFIX}\d{{1,6}}$", max_length=8, examples=[behaviour_id(17)]),
]
ClipId = Annotated[str, Field(pattern=r"^[0-9a-f]{64}\.(mp4|jpg|png)$")]


def limits() -> dict[str, int]:
    """The server's limits that the page needs as numbers (``web/src/limits.json``)."""
    return {"max_group": MAX_GROUP}


class _In(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class _Out(BaseModel):
    model_config = ConfigDict(frozen=True)


class ErrorOut(_Out):
    """Every 4xx answer: one clear sentence."""

    detail: str


# ------------------------------------------------------------------ envs


class TargetOut(_Out):
    """A case study's target: the reward-free behaviour a target env scores
    (`groupwise.envs.targets.Target`)."""

    name: str = Field(examples=["hopper-backflip"])
    base: str = Field(description="the groupwise env it modifies", examples=["Hopper"])
    unit: str = Field(description="what an episode's score counts", examples=["backward turns"])
    threshold: float = Field(description="an episode succeeds when its score reaches this")
    stretch: float = Field(description="the more ambitious level")
    success: str = Field(
        description="when an episode succeeds, in words (the threshold in it)",
        examples=["a split held ≥ 1 s"],
    )
    description: str = Field(description="the definition in one paragraph")


class EnvOut(_Out):
    """An env a session can use by `name`; any other registered Gymnasium id works too."""

    name: str = Field(examples=["Hopper"], description="what POST /api/sessions takes as env")
    gym_id: str = Field(examples=["groupwise/Hopper-v0"])
    kind: Literal["env", "target"] = Field(
        description="env: one of the six fixed-horizon envs; target: a case study's "
        "reward-free env, scored by its target"
    )
    horizon: int = Field(description="steps per episode")
    clip_seconds: float = Field(description="simulated seconds a behaviour covers by default")
    description: str = Field(description="how it differs from the standard env, in one line")
    target: TargetOut | None = None


# ------------------------------------------------------------------ sessions


class SessionCreate(_In):
    env: str | None = Field(
        default=None,
        min_length=1,
        max_length=200,
        examples=["GridWorld"],
        description="the env (required unless settings.dataset names a recorded dataset, "
        "whose own env is the default)",
    )
    mode: Mode = "groupwise"
    settings: SessionSettings = SessionSettings()
    annotator: str = Field(default="", max_length=200)


class Progress(_Out):
    phase: str = Field(description="the step the worker is on, e.g. pool, reward, ppo")
    fraction: float = Field(ge=0, le=1)
    message: str


class Timer(_Out):
    elapsed_s: float = Field(description="seconds the open round's timer has run")
    budget_s: float = Field(description="the round's time budget (0 = no limit)")
    paused: bool
    running: bool = Field(
        description="whether the timer runs now (the round is open, shown and not paused)"
    )
    shown_at: datetime | None = Field(
        default=None,
        description="when a page first showed the current round; its timer runs from then "
        "(null: not shown yet, POST …/rounds/{r}/shown)",
    )


class Counts(_Out):
    comparisons_round: int
    pairs_round: int
    comparisons_total: int
    pairs_total: int


class AgreementOut(_Out):
    """An annotator's agreement with the others on the preference pairs they share (the
    same unordered pair of a round's behaviours), docs/teams.md."""

    kappa: float | None = Field(
        description="Cohen's κ over the shared pairs; null when n = 0 (or when chance "
        "agreement is certain: both used one label throughout)"
    )
    share: float | None = Field(description="share of the n pairs labelled alike; null: n = 0")
    n: int = Field(description="the shared pairs the numbers rest on")


class ModelAgreementOut(_Out):
    """An annotator's strict preferences against the reward model that chose each round's
    pool (rounds after round 0), docs/teams.md."""

    share: float | None = Field(description="share the model orders alike; null: n = 0")
    n: int


class AnnotatorOut(_Out):
    """Someone teaching the session: the owner (id "owner") or an annotator."""

    id: str = Field(examples=["owner", "a-3f9c0b1d2e4a"])
    name: str
    comparisons: int = Field(description="their judgements, not undone, in all rounds")
    pairs: int = Field(description="the preference pairs of those judgements")
    shown_s: float = Field(
        description="seconds from their first showing of each round to its close (or now)"
    )
    agreement: AgreementOut
    model_agreement: ModelAgreementOut


class MeOut(_Out):
    """Who the request's token makes the caller in this session."""

    id: str = Field(description='"owner" or the annotator\'s id')
    name: str
    owner: bool = Field(description="whether they may end rounds, change the session, share it")


class AnnotatorIn(_In):
    name: str = Field(max_length=1000, description="1…100 characters, no control characters")


class AnnotatorCreated(_Out):
    """A new annotator: their token is shown this once (the link carries it)."""

    id: str
    name: str
    token: str
    link: str = Field(description="the page for them: the app's URL ?session=…&token=…")


class SessionState(_Out):
    """Everything a reloaded page needs but the tree."""

    id: str
    env: str
    mode: Mode
    settings: SessionSettings
    annotator: str
    round: int
    rounds: int
    phase: Phase
    progress: Progress
    error: str | None
    failed_phase: Phase | None = Field(
        default=None,
        description="while failed: the step that failed (preparing, training or finishing), "
        "what POST /retry runs again",
    )
    timer: Timer
    counts: Counts
    created_at: datetime
    origin: str | None = Field(default=None, description="the exported session an import came from")
    me: MeOut = Field(description="who the caller is in this session")
    annotators: list[AnnotatorOut] = Field(
        description="the owner, then every annotator of the session (docs/teams.md)"
    )


# ------------------------------------------------------------------ rounds


class TreeNodeOut(_Out):
    """A node of the behaviour tree; leaves carry their behaviour's index, clip and poster."""

    id: str
    kind: Literal["merge", "padding", "leaf"]
    level: int
    size: int
    children: list["TreeNodeOut"]
    behaviour: int | None = None
    clip: str | None = None
    poster: str | None = None


class ClipTiming(_Out):
    """How a pool's clips show its behaviours (docs/app.md, "Clips"; `clips.timing`)."""

    steps: int = Field(description="L, env steps per behaviour")
    stride: int = Field(description="a frame every stride-th step")
    frames: int = Field(description="frames per clip, ⌈steps / stride⌉")
    fps: float = Field(description="playback frames per second, 1 / (stride · step_seconds)")
    seconds: float = Field(description="simulated time a behaviour covers, steps · step_seconds")
    speed: float = Field(description="playback speed relative to simulated time (1: real speed)")
    step_seconds: float = Field(description="dt, simulated seconds per env step")


class RoundTree(_Out):
    round: int
    levels: int
    clip: ClipTiming | None = Field(
        default=None, description="the pool's clip timing (null: a pool from before it)"
    )
    tree: TreeNodeOut
    medoids: dict[str, list[str]] = Field(
        description="inner node id → up to 3 representative behaviour ids"
    )
    compared: list[str] = Field(description="behaviours already in a judgement of the round")


class Edge(_Out):
    a: str
    b: str
    score: float = Field(gt=0, le=1)


class SuggestionRequest(_In):
    exclude: (
        Annotated[
            list[Annotated[list[BehaviourId], Field(max_length=MAX_GROUP)]], Field(max_length=200)
        ]
        | None
    ) = Field(
        default=None,
        description="queries to skip, as consecutive [left ids], [right ids] lists "
        "(one query: [[left], [right]])",
    )


class Suggestion(_Out):
    id: int = Field(
        description="the suggestion's id; a judgement event naming it (suggestion_id) answered it"
    )
    left: list[str]
    right: list[str]
    left_node: str
    right_node: str
    score: float


class SuggestionOut(_Out):
    suggestion: Suggestion | None


# ------------------------------------------------------------------ judgements


class JudgementIn(_In):
    client_id: str = Field(min_length=1, max_length=100, description="unique per comparison")
    round: int = Field(ge=0, le=10_000)
    left: list[BehaviourId] = Field(min_length=1, max_length=MAX_GROUP)
    right: list[BehaviourId] = Field(min_length=1, max_length=MAX_GROUP)
    label: Label
    source: Source
    seconds: float = Field(default=0.0, ge=0, le=86_400)
    edits: int = Field(default=0, ge=0, le=1_000_000)
    annotator: str = Field(
        default="",
        max_length=200,
        description="the owner's free-text name for it; an annotator's judgement takes "
        "their name (docs/teams.md)",
    )


class PairOut(_Out):
    a: str
    b: str
    label: float = Field(description="P(a preferred): 1, 0.5 or 0")


class AnnotatorRef(_Out):
    """Who made a judgement."""

    id: str = Field(description='"owner" or the annotator\'s id')
    name: str


class JudgementOut(_Out):
    id: int
    client_id: str
    round: int
    left: list[str]
    right: list[str]
    label: Label
    source: str
    seconds: float
    edits: int
    annotator: AnnotatorRef
    suggestion_id: int | None = Field(
        default=None, description="the group suggestion it answered (others drop it)"
    )
    created_at: datetime
    undone: bool
    pairs: list[PairOut]


# ------------------------------------------------------------------ pairwise


class PairQuery(_Out):
    left: str
    right: str
    left_clip: str
    right_clip: str
    left_poster: str
    right_poster: str


class PairwiseNext(_Out):
    pair: PairQuery | None
    following: PairQuery | None
    clip: ClipTiming | None = Field(
        default=None, description="the open round's clip timing (null: a pool from before it)"
    )


class PairSkip(_In):
    left: BehaviourId
    right: BehaviourId


# ------------------------------------------------------------------ the final agent


class ContinueIn(_In):
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


class AgentRound(_Out):
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


class AgentVideo(_Out):
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


class AgentTarget(_Out):
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


class AgentOut(_Out):
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


class AgentPickIn(_In):
    """The round whose policy the session hands over (its agent.zip and agent.json)."""

    round: int = Field(ge=0, description="a round of the session with a checkpoint")


# ------------------------------------------------------------------ training


class TrainingPointOut(_Out):
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


class TrainingSummary(_Out):
    """The newest point in words the page shows."""

    round: int
    ppo_steps: int = Field(description="PPO env steps so far")
    pairs: int = Field(description="pairs of the last refit")
    reward_val_accuracy: float | None = Field(description="the last refit's held-out accuracy")
    pool_age: int = Field(description="PPO env steps since the round's pool was sampled")
    true_return: float | None = Field(description="the newest evaluated true return")


class TrainingCurve(_Out):
    """`GET /api/sessions/{id}/training`: the points in the order written, and the newest
    as a summary (null before the first)."""

    points: list[TrainingPointOut]
    summary: TrainingSummary | None


# ------------------------------------------------------------------ misc


class RoundEvent(_Out):
    round: int


class Health(_Out):
    status: Literal["ok"] = "ok"
    worker_pid: int | None = Field(description="the training worker's process id, if running")
    worker_pids: list[int] = Field(
        default_factory=list,
        description="every running training worker's process id (`serve --training-workers`)",
    )
