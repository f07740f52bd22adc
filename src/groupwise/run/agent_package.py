"""The take-away agent's package: ``agent.zip`` and its summary ``agent.json``.

`write_agent_zip` packs a checkpoint (`groupwise.run.checkpoint`) into ``agent.zip``:

    README.md          how to load it, with and without groupwise
    agent.json         `AgentSummary`: env, round, steps, the true return per round (and a
                       target env's episode score), the observation normaliser's constants
    policy.zip         the Stable-Baselines3 PPO policy (it acts on normalised observations)
    vecnormalize.npz   the observation normaliser's running mean and variance
    reward.pt          the learned reward ensemble (`RewardEnsemble.load`)
    config.json        the core's `RunConfig` of the run
    settings.json      the app session's settings (app sessions only)
    rounds.csv         one row per round, as the run wrote it

Reading the summary (`read_summary`) needs neither torch nor SB3: the app's server serves
it; `groupwise.rl.trained_agent.load_agent` loads the policy.
"""

import json
import math
import os
import zipfile
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

from groupwise.config import RunConfig
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
CLIP_OBS = 10.0
EPSILON = 1e-8
"""VecNormalize's observation clip and epsilon (SB3's defaults, which `PPOAgent` uses)."""

ZIP_POLICY, ZIP_NORMALISER, ZIP_REWARD = "policy.zip", "vecnormalize.npz", "reward.pt"
ZIP_CONFIG, ZIP_ROUNDS = "config.json", "rounds.csv"
ROUND_VIDEOS = "agent-rounds"
"""Each round's greedy policy filmed, in a session's directory (`round_video_path`)."""
CHECKPOINTS = "checkpoints"
"""`groupwise.run.checkpoint.CHECKPOINTS` (this module imports no RL)."""


def round_video_path(directory: Path, round_index: int) -> Path:
    """Where round `round_index`'s clip lies in a run's directory."""
    return directory / ROUND_VIDEOS / f"round-{round_index:04d}.mp4"


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


def format_value(value: float) -> str:
    """A value as the summary texts show it: 3 significant digits, thousands grouped (as the
    page's `formatValue`)."""
    rounded = value if abs(value) >= 1000 else float(f"{value:.3g}")
    # half up, as JavaScript's Math.round (Python's round goes to even)
    return f"{math.floor(rounded + 0.5):,}" if abs(rounded) >= 1000 else f"{rounded:g}"


def score_text(
    target: TargetSummary | None,
    measure: str,
    true_return: tuple[float | None, float | None],
    target_score: tuple[float | None, float | None] = (None, None),
) -> str:
    """The evaluation in words: in a target env the episode score first, in its unit, with
    the threshold, then the per-step sum, e.g. "backward turns per episode 0.23 ± 0.05
    (threshold 1) · per-step sum 184 ± 2.62 rad/s"; else "true return 41.5 ± 3.2".
    `true_return` and `target_score` are (mean, sd); None: not measured."""

    def value(mean: float, sd: float | None) -> str:
        return format_value(mean) + ("" if sd is None else f" ± {format_value(sd)}")

    mean, sd = true_return
    if target is None:
        return "not measured" if mean is None else f"{measure} {value(mean, sd)}"
    parts = []
    score, score_sd = target_score
    if score is not None:
        parts.append(
            f"{target.unit} per episode {value(score, score_sd)} "
            f"(threshold {format_value(target.threshold)})"
        )
    if mean is not None:
        parts.append(f"per-step sum {value(mean, sd)} {target.step_unit}")
    return " · ".join(parts) or "not measured"


def _finite(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def summarise(
    cfg: RunConfig,
    records: Sequence[Any],
    frozen: set[int],
    video: VideoSummary | None,
    *,
    round_index: int | None = None,
    chosen_by: str = "last",
    round_videos: Mapping[int, VideoSummary] | None = None,
) -> AgentSummary:
    """The summary of a run whose rounds are `records` (`loop.RoundRecord`s) handing over
    round `round_index`'s policy (default: the last round's); `frozen` holds the indices of
    rounds without feedback, `round_videos` each round's clip.

    Raises:
        KeyError: no record of `round_index`.
    """
    by_round = {int(r.round): r for r in records}
    last = records[-1] if round_index is None else by_round[round_index]
    target = target_of(cfg.loop.env)
    films = round_videos or {}
    return AgentSummary(
        format=FORMAT,
        env=cfg.loop.env,
        round=int(last.round),
        chosen_by=chosen_by,
        env_steps=int(last.env_steps),
        measure=measure_of(cfg.loop.env),
        true_return_mean=_finite(last.true_return_mean),
        true_return_std=_finite(last.true_return_std),
        target=None if target is None else TargetSummary.of(target),
        target_score_mean=_finite(last.target_score_mean),
        target_score_std=_finite(last.target_score_std),
        normalize_obs=cfg.ppo.normalize_obs,
        clip_obs=CLIP_OBS,
        epsilon=EPSILON,
        rounds=tuple(
            RoundSummary(
                round=int(r.round),
                feedback=int(r.round) not in frozen,
                judgements=int(r.judgements),
                pairs_total=int(r.pairs_total),
                env_steps=int(r.env_steps),
                true_return_mean=_finite(r.true_return_mean),
                true_return_std=_finite(r.true_return_std),
                target_score_mean=_finite(r.target_score_mean),
                target_score_std=_finite(r.target_score_std),
                video=films.get(int(r.round)),
            )
            for r in records
        ),
        video=video,
    )


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


class UnknownRoundError(LookupError):
    """The run has no round of that index."""


class NoCheckpointError(LookupError):
    """The round's checkpoint is not (or no longer) in the run's directory."""


def pick_round(directory: Path, round_index: int, chosen_by: str = "person") -> AgentSummary:
    """Hand over round `round_index`'s policy instead: ``agent.zip`` repacked from that
    round's checkpoint and ``agent.json`` rewritten (its round, steps and scores; `chosen_by`;
    the video is the round's clip when it was filmed). The rounds' records are the
    summary's, so nothing is evaluated again.

    Raises:
        FileNotFoundError: the run has no summary (no agent published).
        UnknownRoundError: the summary has no round `round_index`.
        NoCheckpointError: its checkpoint is missing (the reason in the message).
    """
    summary = read_summary(directory)
    if summary is None:
        raise FileNotFoundError(f"{directory} has no {SUMMARY_FILE}")
    rounds = {r.round: r for r in summary.rounds}
    if round_index not in rounds:
        raise UnknownRoundError(
            f"no round {round_index}: the run has rounds {min(rounds)} to {max(rounds)}"
        )
    checkpoint = directory / CHECKPOINTS / f"round-{round_index:04d}"
    missing = [
        n for n in (ZIP_POLICY, ZIP_NORMALISER, ZIP_REWARD) if not (checkpoint / n).is_file()
    ]
    if missing:
        raise NoCheckpointError(
            f"round {round_index}'s checkpoint has no {', '.join(missing)} (it was not kept, "
            "or the session was imported without its checkpoints): its policy cannot be "
            "packaged"
        )
    chosen = rounds[round_index]
    video = chosen.video or (summary.video if summary.round == round_index else None)
    picked = replace(
        summary,
        round=round_index,
        chosen_by=chosen_by,
        env_steps=chosen.env_steps,
        true_return_mean=chosen.true_return_mean,
        true_return_std=chosen.true_return_std,
        target_score_mean=chosen.target_score_mean,
        target_score_std=chosen.target_score_std,
        video=video,
    )
    write_agent_zip(directory / AGENT_ZIP, checkpoint, picked, directory)
    write_summary(directory, picked)
    return picked


def write_agent_zip(
    path: Path,
    checkpoint: Path,
    summary: AgentSummary,
    run_dir: Path,
) -> None:
    """Pack `checkpoint`'s policy, normaliser and reward ensemble with `summary`, a README,
    and `run_dir`'s ``config.json``, ``rounds.csv`` and ``settings.json`` (when present)
    into `path`, replaced atomically."""
    partial = path.with_name(f".{path.name}.partial")
    with zipfile.ZipFile(partial, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("README.md", readme(summary))
        archive.writestr(SUMMARY_FILE, summary.to_json() + "\n")
        for name in (ZIP_POLICY, ZIP_NORMALISER, ZIP_REWARD):
            archive.write(checkpoint / name, name)
        for name in (ZIP_CONFIG, ZIP_ROUNDS, SETTINGS_FILE):
            if (run_dir / name).is_file():
                archive.write(run_dir / name, name)
    os.replace(partial, path)


def readme(summary: AgentSummary) -> str:
    """The zip's README.md: what it holds and how to load it."""
    judged = sum(r.judgements for r in summary.rounds)
    feedback = sum(r.feedback for r in summary.rounds)
    score = score_text(
        summary.target,
        summary.measure,
        (summary.true_return_mean, summary.true_return_std),
        (summary.target_score_mean, summary.target_score_std),
    )
    target = summary.target
    scored = (
        f"Evaluated after round {summary.round} (the greedy policy over the run's evaluation "
        f"episodes): **{score}**."
    )
    if target is not None:
        scored += (
            f"\n\nThe target {target.name} counts {target.unit} per episode; an episode "
            f"succeeds from {format_value(target.threshold)} (stretch: "
            f"{format_value(target.stretch)}). The per-step sum adds up the target's per-step "
            "scores (the true reward a simulated teacher perceives); the episode score says "
            "whether teaching worked."
        )
    evaluated = (
        f'"{target.unit} per episode … (threshold {format_value(target.threshold)}) · '
        f'per-step sum … {target.step_unit}"'
        if target is not None
        else '"true return … ± …"'
    )
    per_round = summary.measure + (" and the episode score" if target is not None else "")
    return f"""# groupwise agent: {summary.env}, round {summary.round}

A PPO policy trained by groupwise on a reward model learned from preferences:
{judged} judgements over {feedback} feedback round(s), {summary.env_steps:,} PPO env steps
in all.

{scored}

## Load it with groupwise

```python
import groupwise

agent = groupwise.load_agent("agent.zip")
action = agent.predict(obs)                 # one observation, or a batch (B, obs_dim)
result = agent.evaluate("{summary.env}", episodes=5, seed=0)   # or an env, or a factory
print(result)                               # {evaluated}
result.returns                              # each episode's true return (the per-step sum)
result.scores                               # a target env's episode scores (None elsewhere)
reward = agent.reward_model()               # the learned reward ensemble
```

`predict` applies the saved observation normaliser before the policy, greedy by default
(`deterministic=False` samples). `evaluate` plays whole episodes and returns each one's true
return (the sum of ``info["true_reward"]``, a target env's per-step scores) and, in a
target env, its episode score (``info["target_total"]`` at the end, in the target's unit).

## Load it without groupwise

```python
import numpy as np
from stable_baselines3 import PPO

model = PPO.load("policy.zip", device="cpu")
norm = np.load("vecnormalize.npz")
def act(obs):
    x = np.clip((obs - norm["obs_mean"]) / np.sqrt(norm["obs_var"] + {summary.epsilon}),
                -{summary.clip_obs}, {summary.clip_obs})
    return model.predict(x, deterministic=True)[0]
```

(observations are normalised only when `agent.json`'s `normalize_obs` is true).

## Files

| file | holds |
|---|---|
| `policy.zip` | the Stable-Baselines3 PPO policy (`PPO.load`); it acts on normalised observations |
| `vecnormalize.npz` | the observation normaliser: `obs_mean`, `obs_var` (and return statistics) |
| `reward.pt` | the learned reward ensemble (`groupwise.RewardEnsemble.load`) |
| `agent.json` | env, round, steps, the {per_round} per round, the normaliser's constants |
| `config.json` | the run's configuration (`groupwise.RunConfig.load`) |
| `settings.json` | the app session's settings (sessions of the app only) |
| `rounds.csv` | one row per round, as `groupwise train` and the app write it |
"""
