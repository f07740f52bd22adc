"""The agent file's names and its summary ``agent.json`` (`AgentSummary`): what the agent
is, how it came about, and how its observations are normalised."""

import json
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from groupwise.envs import TARGETS, Target, resolve_id

FORMAT = "groupwise.agent/1"
AGENT_ZIP = "agent.zip"
"""The download's name in a session's directory."""
AGENT_VIDEO = "agent.mp4"
"""The final agent's video in a session's directory."""
SUMMARY_FILE = "agent.json"
"""The summary, in the zip and beside it in the session's directory."""
SETTINGS_FILE = "settings.json"
"""An app session's settings, beside its ``config.json``."""
ZIP_POLICY, ZIP_NORMALISER, ZIP_REWARD = "policy.zip", "vecnormalize.npz", "reward.pt"
ZIP_CONFIG, ZIP_ROUNDS = "config.json", "rounds.csv"
ROUND_VIDEOS = "agent-rounds"
"""Each round's greedy policy filmed, in a session's directory (`round_video_path`)."""


def round_video_path(directory: Path, round_index: int) -> Path:
    """Where round `round_index`'s clip lies in a run's directory."""
    return directory / ROUND_VIDEOS / f"round-{round_index:04d}.mp4"


@dataclass(frozen=True)
class ObsNormalisation:
    """How the policy saw its observations in training: ``clip((obs - obs_mean) /
    sqrt(obs_var + epsilon), -clip_obs, clip_obs)`` with the running ``obs_mean`` and
    ``obs_var`` of ``vecnormalize.npz``; the raw observations when `normalize_obs` is false.
    The trainer states it (`groupwise.rl.agent_file.normalisation`); the file records it, so
    a reader needs no RL library to apply it."""

    normalize_obs: bool
    clip_obs: float
    epsilon: float


@dataclass(frozen=True)
class RoundSummary:
    """One round of the run, as the page's chart shows it."""

    round: int
    feedback: bool
    """False for a round without feedback: PPO on the frozen learned reward only."""
    judgements: int
    pairs_total: int
    env_steps: int
    true_return_mean: float | None
    """None when the round was not evaluated (`eval_episodes` = 0)."""
    true_return_std: float | None
    target_score_mean: float | None = None
    """A target env's episode score after the round, in `TargetSummary.unit`; None for
    other envs, rounds not evaluated, and summaries written before it was recorded."""
    target_score_std: float | None = None
    video: "VideoSummary | None" = None
    """The round's greedy policy filmed (``agent-rounds/round-NNNN.mp4``), the clip a person
    picks the take-away agent by; None where it was not filmed."""


@dataclass(frozen=True)
class VideoSummary:
    """The agent's video (`clips.episode_video.EpisodeVideo`) and its episode's return."""

    file: str
    """Its path in the run's directory."""
    seconds: float
    fps: float
    frames: int
    width: int
    height: int
    episode_return: float
    """The filmed episode's true return (a target env: the sum of its per-step scores)."""
    target_score: float | None = None
    """A target env's score of the filmed episode, in `TargetSummary.unit`."""


@dataclass(frozen=True)
class TargetSummary:
    """The target a target env scores (`groupwise.envs.targets.Target`), as the summary
    states it."""

    name: str
    unit: str
    """What the episode score counts, e.g. "backward turns"."""
    step_unit: str
    """The unit of a per-step score and of their sum, the true return, e.g. "rad/s"."""
    threshold: float
    """An episode succeeds when its score reaches this."""
    stretch: float

    @classmethod
    def of(cls, target: Target) -> "TargetSummary":
        return cls(
            name=target.name,
            unit=target.unit,
            step_unit=target.step_unit,
            threshold=target.threshold,
            stretch=target.stretch,
        )


@dataclass(frozen=True)
class AgentSummary:
    """``agent.json``: what the agent is and how it came about."""

    format: str
    env: str
    round: int
    """The round whose checkpoint this is: the last row of ``rounds.csv`` unless a teacher
    or a person chose another (`chosen_by`)."""
    env_steps: int
    measure: str
    """What `true_return_mean` measures (`measure_of`): "true return", or in a target env
    the sum of the per-step scores, e.g. "per-step score sum (rad/s)"."""
    true_return_mean: float | None
    true_return_std: float | None
    normalize_obs: bool
    clip_obs: float
    epsilon: float
    rounds: tuple[RoundSummary, ...]
    video: VideoSummary | None = None
    target: TargetSummary | None = None
    """The target of a target env (None for other envs)."""
    target_score_mean: float | None = None
    """The last round's episode score in the target's unit (mean, sd over the evaluation
    episodes): whether teaching worked. None where `RoundSummary.target_score_mean` is."""
    target_score_std: float | None = None
    chosen_by: str = "last"
    """Who chose `round`: "last" (nobody: the last round), "teacher" (the run's simulated
    teacher, `groupwise.run.takeaway`) or "person" (on the app's results page)."""

    @property
    def normalisation(self) -> ObsNormalisation:
        return ObsNormalisation(self.normalize_obs, self.clip_obs, self.epsilon)

    @property
    def last_round(self) -> int:
        return self.rounds[-1].round if self.rounds else self.round

    def to_json(self) -> str:
        return json.dumps(asdict(self), indent=1)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "AgentSummary":
        """Raises ValueError for another format, KeyError/TypeError for a broken one."""
        if data.get("format") != FORMAT:
            raise ValueError(f"not a groupwise agent summary ({data.get('format')!r})")
        video, target = data.get("video"), data.get("target")
        measure = data["measure"]
        if measure.startswith(OLD_TARGET_MEASURE):
            # written before the episode score was recorded: the value was always the sum of
            # the per-step scores (issue 23)
            measure = measure_of(data["env"])
        return cls(
            **{k: v for k, v in data.items() if k not in ("rounds", "video", "target", "measure")},
            measure=measure,
            rounds=tuple(_round_summary(r) for r in data["rounds"]),
            video=None if video is None else VideoSummary(**video),
            target=None if target is None else TargetSummary(**target),
        )


def _round_summary(data: dict[str, Any]) -> RoundSummary:
    video = data.get("video")
    return RoundSummary(
        **{k: v for k, v in data.items() if k != "video"},
        video=None if video is None else VideoSummary(**video),
    )


OLD_TARGET_MEASURE = "target score ("
"""How summaries before issue 23 mislabelled a target env's per-step score sum."""


def target_of(env: str) -> Target | None:
    """The target a target env (short name or Gymnasium id) scores; None for other envs."""
    try:
        wanted = resolve_id(env)
    except ValueError:
        return None
    for target in TARGETS.values():
        if resolve_id(target.env) == wanted:
            return target
    return None


def measure_of(env: str) -> str:
    """What an env's true return is: "true return", or in a target env the sum of its
    per-step scores, in their unit (the episode score is another number:
    docs/case-studies.md)."""
    target = target_of(env)
    return "true return" if target is None else f"per-step score sum ({target.step_unit})"


def read_summary(directory: Path) -> AgentSummary | None:
    """The summary written beside a run's ``agent.zip``, or None when there is none."""
    try:
        return AgentSummary.from_dict(json.loads((directory / SUMMARY_FILE).read_text()))
    except FileNotFoundError:
        return None


def write_summary(directory: Path, summary: AgentSummary) -> None:
    """``agent.json`` in `directory`, replaced atomically."""
    partial = directory / f".{SUMMARY_FILE}.partial"
    partial.write_text(summary.to_json() + "\n")
    partial.replace(directory / SUMMARY_FILE)
