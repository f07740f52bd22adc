"""A trained agent loaded from its ``agent.zip`` (`groupwise.agent_file`), for use
elsewhere (docs/library.md): `load_agent(path)` reads it back as a `TrainedAgent` with
`predict(obs)` (the saved normaliser applied first) and `evaluate(env, episodes, seed)`
(an `AgentEvaluation`: the true returns and, in a target env, the episode scores).
"""

import io
import json
import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from groupwise.agent_file.archive import read_agent_zip
from groupwise.agent_file.summary import (
    ZIP_CONFIG,
    ZIP_NORMALISER,
    ZIP_POLICY,
    ZIP_REWARD,
    AgentSummary,
    TargetSummary,
    measure_of,
)
from groupwise.agent_file.text import score_text
from groupwise.config import RunConfig
from groupwise.envs import TARGET_TOTAL_KEY, TRUE_REWARD_KEY, Target, make_env
from groupwise.envs.targets import TargetScoreInfo
from groupwise.types import FloatArray


@dataclass(frozen=True)
class AgentEvaluation:
    """What `TrainedAgent.evaluate` measured; ``str()`` says it in words, e.g. "backward
    turns per episode 0.23 ± 0.05 (threshold 1) · per-step sum 184 ± 2.62 rad/s"."""

    returns: FloatArray  # (E,) each episode's true return: its per-step true rewards summed
    scores: FloatArray | None  # (E,) a target env's episode scores, in `target.unit`; else None
    target: Target | None
    """The target the env scores, where known (a target env made by name, or wrapped in
    `TargetScoreInfo`)."""
    measure: str = "true return"
    """What `returns` measures (`agent_file.summary.measure_of`)."""

    def __str__(self) -> str:
        target = None if self.target is None else TargetSummary.of(self.target)
        scores = (None, None) if self.scores is None else _mean_sd(self.scores)
        return score_text(target, self.measure, _mean_sd(self.returns), scores)


def _mean_sd(values: FloatArray) -> tuple[float, float]:
    return float(np.mean(values)), float(np.std(values))


def _target_of_env(env: gym.Env[Any, Any]) -> Target | None:
    """The target of an env wrapped in `TargetScoreInfo` (any depth), else None."""
    layer: Any = env
    while isinstance(layer, gym.Wrapper):
        if isinstance(layer, TargetScoreInfo):
            return layer.target
        layer = layer.env
    return None


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
    ) -> AgentEvaluation:
        """`episodes` whole episodes in `env` (an env, a factory, an env name, or None for
        the env it was trained on), episode i reset with seed `seed` + i: each one's true
        return, the sum of ``info["true_reward"]`` where the env reports it (groupwise envs;
        a target env's per-step scores), else of the env's reward; and, where the env
        reports ``info["target_total"]`` (a target env), each one's episode score, the
        value at its last step in the target's unit."""
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
            played = [self._episode(made, seed + i, deterministic) for i in range(episodes)]
            target = _target_of_env(made)
        finally:
            if own:
                made.close()
        scores = np.array([score for _, score in played])
        return AgentEvaluation(
            returns=np.array([total for total, _ in played]),
            scores=None if np.isnan(scores).all() else scores,
            target=target,
            measure="true return" if target is None else measure_of(target.env),
        )

    def _episode(
        self, env: gym.Env[Any, Any], seed: int, deterministic: bool
    ) -> tuple[float, float]:
        """The true return and the episode score (nan where the env has none) of one."""
        obs, _ = env.reset(seed=seed)
        total, score, done = 0.0, math.nan, False
        while not done:
            obs, reward, terminated, truncated, info = env.step(self.predict(obs, deterministic))
            total += float(info.get(TRUE_REWARD_KEY, reward))
            score = float(info.get(TARGET_TOTAL_KEY, math.nan))
            done = bool(terminated or truncated)
        return total, score

    def reward_model(self) -> Any:
        """The learned reward ensemble (`groupwise.RewardEnsemble`) saved with the policy."""
        import tempfile

        from groupwise.reward import RewardEnsemble

        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / ZIP_REWARD
            path.write_bytes(self._files[ZIP_REWARD])
            return RewardEnsemble.load(path)

    def config(self) -> RunConfig:
        """The run's configuration."""
        return RunConfig.from_dict(json.loads(self._files[ZIP_CONFIG]))


def load_agent(path: str | os.PathLike[str]) -> TrainedAgent:
    """Load an ``agent.zip`` (from the app's "Download agent", or a session directory).

    Raises:
        FileNotFoundError: no such file.
        ValueError: not a groupwise agent file.
    """
    from stable_baselines3 import PPO

    archive = read_agent_zip(path)
    files = archive.files
    model = PPO.load(io.BytesIO(files[ZIP_POLICY]), device="cpu")
    with np.load(io.BytesIO(files[ZIP_NORMALISER])) as norm:
        mean, var = np.asarray(norm["obs_mean"]), np.asarray(norm["obs_var"])
    return TrainedAgent(model, mean, var, archive.summary, files)
