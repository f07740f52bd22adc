"""A trained agent as one file: the end of a session, for use elsewhere (docs/library.md).

`write_agent_zip` packs a checkpoint (`groupwise.run.checkpoint`) into ``agent.zip``:

    README.md          how to load it, with and without groupwise
    agent.json         `AgentSummary`: env, round, steps, the true return per round, the
                       observation normaliser's constants
    policy.zip         the Stable-Baselines3 PPO policy (it acts on normalised observations)
    vecnormalize.npz   the observation normaliser's running mean and variance
    reward.pt          the learned reward ensemble (`RewardEnsemble.load`)
    config.json        the core's `RunConfig` of the run
    settings.json      the app session's settings (app sessions only)
    rounds.csv         one row per round, as the run wrote it

`load_agent(path)` reads it back as a `TrainedAgent` with `predict(obs)` (the saved
normaliser applied first) and `evaluate(env, episodes, seed)`. Only reading the summary
(`read_summary`) is cheap: the policy loads SB3 and torch.
"""

import io
import json
import math
import os
import zipfile
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from groupwise.config import RunConfig
from groupwise.envs import TARGETS, TRUE_REWARD_KEY, make_env, resolve_id
from groupwise.types import FloatArray

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

_POLICY, _NORMALISER, _REWARD = "policy.zip", "vecnormalize.npz", "reward.pt"
_CONFIG, _ROUNDS = "config.json", "rounds.csv"


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


@dataclass(frozen=True)
class VideoSummary:
    """The agent's video (`clips.episode_video.EpisodeVideo`) and its episode's return."""

    file: str
    seconds: float
    fps: float
    frames: int
    width: int
    height: int
    episode_return: float


@dataclass(frozen=True)
class AgentSummary:
    """``agent.json``: what the agent is and how it came about."""

    format: str
    env: str
    round: int
    """The round whose checkpoint this is (the last row of ``rounds.csv``)."""
    env_steps: int
    measure: str
    """What `true_return_mean` measures: "true return", or a target env's score."""
    true_return_mean: float | None
    true_return_std: float | None
    normalize_obs: bool
    clip_obs: float
    epsilon: float
    rounds: tuple[RoundSummary, ...]
    video: VideoSummary | None = None

    def to_json(self) -> str:
        return json.dumps(asdict(self), indent=1)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "AgentSummary":
        """Raises ValueError for another format, KeyError/TypeError for a broken one."""
        if data.get("format") != FORMAT:
            raise ValueError(f"not a groupwise agent summary ({data.get('format')!r})")
        video = data.get("video")
        return cls(
            **{k: v for k, v in data.items() if k not in ("rounds", "video")},
            rounds=tuple(RoundSummary(**r) for r in data["rounds"]),
            video=None if video is None else VideoSummary(**video),
        )


def measure_of(env: str) -> str:
    """What an env's true return is: a target env's score names its unit (docs/case-studies.md)."""
    try:
        wanted = resolve_id(env)
    except ValueError:
        return "true return"
    for target in TARGETS.values():
        if resolve_id(target.env) == wanted:
            return f"target score ({target.unit})"
    return "true return"


def _finite(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def summarise(
    cfg: RunConfig,
    records: Sequence[Any],
    frozen: set[int],
    video: VideoSummary | None,
) -> AgentSummary:
    """The summary of a run whose rounds are `records` (`loop.RoundRecord`s); `frozen`
    holds the indices of rounds without feedback."""
    last = records[-1]
    return AgentSummary(
        format=FORMAT,
        env=cfg.loop.env,
        round=int(last.round),
        env_steps=int(last.env_steps),
        measure=measure_of(cfg.loop.env),
        true_return_mean=_finite(last.true_return_mean),
        true_return_std=_finite(last.true_return_std),
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
        for name in (_POLICY, _NORMALISER, _REWARD):
            archive.write(checkpoint / name, name)
        for name in (_CONFIG, _ROUNDS, SETTINGS_FILE):
            if (run_dir / name).is_file():
                archive.write(run_dir / name, name)
    os.replace(partial, path)


def readme(summary: AgentSummary) -> str:
    """The zip's README.md: what it holds and how to load it."""
    judged = sum(r.judgements for r in summary.rounds)
    feedback = sum(r.feedback for r in summary.rounds)
    score = (
        "not measured"
        if summary.true_return_mean is None
        else f"{summary.true_return_mean:.4g} ± {summary.true_return_std or 0:.3g}"
    )
    return f"""# groupwise agent: {summary.env}, round {summary.round}

A PPO policy trained by groupwise on a reward model learned from preferences:
{judged} judgements over {feedback} feedback round(s), {summary.env_steps:,} PPO env steps
in all. Its {summary.measure} after round {summary.round}: {score}.

## Load it with groupwise

```python
import groupwise

agent = groupwise.load_agent("agent.zip")
action = agent.predict(obs)                 # one observation, or a batch (B, obs_dim)
returns = agent.evaluate("{summary.env}", episodes=5, seed=0)   # or an env, or a factory
reward = agent.reward_model()               # the learned reward ensemble
```

`predict` applies the saved observation normaliser before the policy, greedy by default
(`deterministic=False` samples). `evaluate` returns each episode's true return (a target
env's score) as an array.

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
| `agent.json` | env, round, steps, the {summary.measure} per round, the normaliser's constants |
| `config.json` | the run's configuration (`groupwise.RunConfig.load`) |
| `settings.json` | the app session's settings (sessions of the app only) |
| `rounds.csv` | one row per round, as `groupwise train` and the app write it |
"""


class TrainedAgent:
    """A policy loaded from an ``agent.zip`` (`load_agent`)."""

    def __init__(
        self,
        model: Any,
        obs_mean: FloatArray,
        obs_var: FloatArray,
        summary: AgentSummary,
        files: dict[str, bytes],
    ) -> None:
        self.model = model
        """The Stable-Baselines3 PPO model (acting on normalised observations)."""
        self.summary = summary
        self.obs_mean = obs_mean
        self.obs_var = obs_var
        self._files = files

    @property
    def env(self) -> str:
        """The env it was trained on (a name `groupwise.envs.make_env` makes)."""
        return self.summary.env

    def make_env(self) -> gym.Env[Any, Any]:
        """A fresh instance of the env it was trained on."""
        return make_env(self.env)

    def normalise(self, obs: np.ndarray) -> np.ndarray:
        """Observations as the policy saw them in training."""
        obs = np.asarray(obs, dtype=np.float32)
        if not self.summary.normalize_obs:
            return obs
        scaled = (obs - self.obs_mean) / np.sqrt(self.obs_var + self.summary.epsilon)
        clip = self.summary.clip_obs
        return np.clip(scaled, -clip, clip).astype(np.float32)

    def predict(self, obs: np.ndarray, deterministic: bool = True) -> np.ndarray:
        """The action for one raw observation (obs_dim,), or actions (B, …) for a batch."""
        action, _ = self.model.predict(self.normalise(obs), deterministic=deterministic)
        return np.asarray(action)

    def evaluate(
        self,
        env: gym.Env[Any, Any] | Callable[[], gym.Env[Any, Any]] | str | None = None,
        episodes: int = 5,
        seed: int = 0,
        deterministic: bool = True,
    ) -> FloatArray:
        """The true return of each of `episodes` whole episodes, (episodes,): an env, a
        factory, an env name, or None for the env it was trained on; episode i is reset
        with seed `seed` + i. The return sums ``info["true_reward"]`` where the env reports
        it (groupwise envs; a target env's score), else the env's reward."""
        if episodes < 1:
            raise ValueError(f"need at least one episode, got {episodes}")
        own = not isinstance(env, gym.Env)
        if env is None:
            made = self.make_env()
        elif isinstance(env, str):
            made = make_env(env)
        elif isinstance(env, gym.Env):
            made = env
        else:
            made = env()
        try:
            return np.array([self._episode(made, seed + i, deterministic) for i in range(episodes)])
        finally:
            if own:
                made.close()

    def _episode(self, env: gym.Env[Any, Any], seed: int, deterministic: bool) -> float:
        obs, _ = env.reset(seed=seed)
        total, done = 0.0, False
        while not done:
            obs, reward, terminated, truncated, info = env.step(self.predict(obs, deterministic))
            total += float(info.get(TRUE_REWARD_KEY, reward))
            done = bool(terminated or truncated)
        return total

    def reward_model(self) -> Any:
        """The learned reward ensemble (`groupwise.RewardEnsemble`) saved with the policy."""
        import tempfile

        from groupwise.reward import RewardEnsemble

        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / _REWARD
            path.write_bytes(self._files[_REWARD])
            return RewardEnsemble.load(path)

    def config(self) -> RunConfig:
        """The run's configuration."""
        return RunConfig.from_dict(json.loads(self._files[_CONFIG]))


def load_agent(path: str | os.PathLike[str]) -> TrainedAgent:
    """Load an ``agent.zip`` (from the app's "Download agent", or a session directory).

    Raises:
        FileNotFoundError: no such file.
        ValueError: not a groupwise agent file.
    """
    from stable_baselines3 import PPO

    try:
        with zipfile.ZipFile(path) as archive:
            files = {name: archive.read(name) for name in archive.namelist()}
    except zipfile.BadZipFile as error:
        raise ValueError(f"{path} is not a zip file: {error}") from None
    missing = [n for n in (SUMMARY_FILE, _POLICY, _NORMALISER) if n not in files]
    if missing:
        raise ValueError(f"{path} is not a groupwise agent: it lacks {', '.join(missing)}")
    summary = AgentSummary.from_dict(json.loads(files[SUMMARY_FILE]))
    model = PPO.load(io.BytesIO(files[_POLICY]), device="cpu")
    with np.load(io.BytesIO(files[_NORMALISER])) as norm:
        mean, var = np.asarray(norm["obs_mean"]), np.asarray(norm["obs_var"])
    return TrainedAgent(model, mean, var, summary, files)
