"""The reward-model ensemble as the rest of the system sees it: numpy in, numpy out (SPEC §3).

Inputs are the concatenated [obs ; encoded action] of each step (one-hot for discrete
actions, see `groupwise.envs.spaces`), or with `RewardConfig.use_actions` off the
observation alone (the actions are still taken and shape-checked).
Every prediction runs under `torch.inference_mode` and never changes the input normaliser;
only `fit` (in `bradley_terry`) and `update_normalizer` / `refit_normalizer` do.

Pickling: a `RewardEnsemble` (and so its bound `mean_reward`) pickles and cloudpickles like
any `nn.Module`, e.g. into SB3 subprocess VecEnvs; the copy is a snapshot that later fits in
the parent process do not reach. Not thread-safe: `fit` changes the weights in place, so a
thread predicting during a fit sees a model in between.
"""

import dataclasses
import logging
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import torch
from torch import Tensor

from groupwise.config import RewardConfig
from groupwise.envs.spaces import action_dim, observation_dim
from groupwise.reward.network import RewardNet, member_mlp
from groupwise.types import FloatArray

log = logging.getLogger(__name__)

FORMAT_VERSION = 1
"""Version of the file `save` writes; `load` refuses other versions."""
_CHUNK_ROWS = 1 << 16
"""Steps per forward pass in `step_rewards` / `returns`, bounding memory on huge inputs."""


class RewardEnsemble:
    """K reward MLPs over [obs ; act] (or obs alone) sharing one running input normaliser.

    `net` is the underlying `torch.nn.Module` (used by training); everything else takes and
    returns numpy arrays. `l2_weight` is the current adaptive L2 coefficient; it belongs to
    the ensemble so that it carries over from one fit (round) to the next and is saved.
    """

    def __init__(
        self, obs_dim: int, act_dim: int, cfg: RewardConfig, rng: np.random.Generator
    ) -> None:
        """Draw the initial weights from `rng` (through a seeded `torch.Generator`).

        Raises ValueError unless obs_dim >= 1, act_dim >= 0 and ensemble_size >= 1.
        """
        if obs_dim < 1 or act_dim < 0 or cfg.ensemble_size < 1:
            raise ValueError(
                f"invalid ensemble: obs_dim {obs_dim}, act_dim {act_dim}, "
                f"{cfg.ensemble_size} members"
            )
        self.obs_dim = obs_dim
        self.act_dim = act_dim
        self.cfg = cfg
        generator = torch.Generator().manual_seed(int(rng.integers(0, 2**63 - 1)))
        self.net = RewardNet(
            cfg.ensemble_size,
            obs_dim + act_dim if cfg.use_actions else obs_dim,
            cfg.hidden_sizes,
            cfg.activation,
            generator,
            self._split,
            cfg.action_term,
        )
        self.net.eval()
        self.l2_weight = float(cfg.initial_l2)
        self.output_shift = torch.zeros(cfg.ensemble_size, 1)
        self.output_scale = torch.ones(cfg.ensemble_size, 1)

    @classmethod
    def for_env(
        cls, make_env: Callable[[], gym.Env], cfg: RewardConfig, rng: np.random.Generator
    ) -> "RewardEnsemble":
        """An ensemble over the [obs ; encoded action] features of the env `make_env` makes."""
        probe = make_env()
        try:
            obs_dim = observation_dim(probe.observation_space)
            act_dim = action_dim(probe.action_space)
        finally:
            probe.close()
        return cls(obs_dim, act_dim, cfg, rng)

    @property
    def size(self) -> int:
        """K, the number of members."""
        return self.net.mlp.members

    @property
    def in_dim(self) -> int:
        return self.obs_dim + self.act_dim if self.cfg.use_actions else self.obs_dim

    @property
    def _split(self) -> int | None:
        """Where members that separate the action (`RewardConfig.action_term`) split their
        inputs: after the observation; None for one MLP over all inputs."""
        separate = self.cfg.use_actions and self.cfg.action_term != "joint" and self.act_dim > 0
        return self.obs_dim if separate else None

    # ---------------------------------------------------------------- prediction

    def features(self, obs: np.ndarray, acts: np.ndarray) -> Tensor:
        """[obs ; acts] as a float32 tensor (..., obs_dim + act_dim).

        Raises ValueError when the widths or the leading (batch) shapes disagree.
        """
        obs = np.asarray(obs, dtype=np.float32)
        acts = np.asarray(acts, dtype=np.float32)
        if obs.shape[-1:] != (self.obs_dim,) or acts.shape[-1:] != (self.act_dim,):
            raise ValueError(
                f"expected obs (..., {self.obs_dim}) and acts (..., {self.act_dim}), "
                f"got {obs.shape} and {acts.shape}"
            )
        if obs.shape[:-1] != acts.shape[:-1]:
            raise ValueError(f"obs {obs.shape} and acts {acts.shape} differ in batch shape")
        if not self.cfg.use_actions:
            return torch.from_numpy(obs)
        return torch.from_numpy(np.concatenate([obs, acts], axis=-1))

    def step_rewards(self, obs: np.ndarray, acts: np.ndarray) -> FloatArray:
        """Per-member per-step rewards: obs (*batch, obs_dim), acts (*batch, act_dim) ->
        (K, *batch) float32."""
        x = self.features(obs, acts)
        batch = x.shape[:-1]
        rows = x.reshape(-1, self.in_dim)
        with torch.inference_mode():
            out = torch.cat([self.net(chunk) for chunk in rows.split(_CHUNK_ROWS)], dim=1)
        return out.reshape(self.size, *batch).numpy()

    def returns(self, obs: np.ndarray, acts: np.ndarray) -> FloatArray:
        """Predicted return of each fragment under each member: obs (N, L, obs_dim),
        acts (N, L, act_dim) -> (N, K) float32, the sum of the per-step rewards.

        Raises ValueError for inputs that are not 3-d.
        """
        if np.ndim(obs) != 3 or np.ndim(acts) != 3:
            raise ValueError(
                f"expected (N, L, dim) fragments, got {np.shape(obs)} and {np.shape(acts)}"
            )
        return np.ascontiguousarray(self.step_rewards(obs, acts).sum(axis=-1).T)

    def mean_reward(self, obs: np.ndarray, acts: np.ndarray) -> FloatArray:
        """Ensemble-mean per-step reward: obs (B, obs_dim), acts (B, act_dim) -> (B,) float32.

        This is the reward PPO trains on, called every env step: one forward pass over all
        members, no per-member Python loop, and only the cheapest shape check.

        Raises ValueError when the inputs are not (B, obs_dim) and (B, act_dim).
        """
        obs = np.asarray(obs, dtype=np.float32)
        acts = np.asarray(acts, dtype=np.float32)
        x = torch.from_numpy(np.concatenate([obs, acts], axis=-1))
        if x.dim() != 2 or x.shape[1] != self.obs_dim + self.act_dim:
            raise ValueError(
                f"expected obs (B, {self.obs_dim}) and acts (B, {self.act_dim}), "
                f"got {np.shape(obs)} and {np.shape(acts)}"
            )
        if not self.cfg.use_actions:
            x = x[:, : self.obs_dim]
        with torch.inference_mode():
            out = (self.net(x) - self.output_shift) / self.output_scale
            return out.mean(dim=0).numpy()

    def reinitialise(self, rng: np.random.Generator) -> None:
        """Fresh member weights drawn from `rng` and the initial L2 weight (a refit from
        scratch, `RewardConfig.warm_start` off); the normaliser is left to `fit`."""
        generator = torch.Generator().manual_seed(int(rng.integers(0, 2**63 - 1)))
        cfg = self.cfg
        self.net.mlp = member_mlp(
            cfg.ensemble_size,
            self.in_dim,
            cfg.hidden_sizes,
            cfg.activation,
            generator,
            self._split,
            cfg.action_term,
        )
        self.net.eval()
        self.l2_weight = float(cfg.initial_l2)

    def standardise_output(self, obs: np.ndarray, acts: np.ndarray) -> None:
        """Centre and scale each member's reward to mean 0 and sd 1 over these steps (obs
        (..., obs_dim), acts (..., act_dim)) in `mean_reward`, the reward PPO sees; the
        members' raw outputs (`step_rewards`, `returns`, what training and query selection
        use) stay as they are. Called after every fit when `RewardConfig.standardise_output`."""
        out = self.step_rewards(obs, acts).reshape(self.size, -1).astype(np.float64)
        if out.shape[1] == 0:
            return
        self.output_shift = torch.as_tensor(out.mean(axis=1, keepdims=True), dtype=torch.float32)
        scale = np.maximum(out.std(axis=1, keepdims=True), 1e-6)
        self.output_scale = torch.as_tensor(scale, dtype=torch.float32)

    # ---------------------------------------------------------------- normaliser

    def update_normalizer(self, obs: np.ndarray, acts: np.ndarray) -> None:
        """Fold the steps obs (..., obs_dim), acts (..., act_dim) into the input statistics."""
        self.net.norm.update(self.features(obs, acts))
        self._uncentre_actions()

    def refit_normalizer(self, obs: np.ndarray, acts: np.ndarray) -> None:
        """Reset the input statistics to exactly those of these steps (each counted once)."""
        x = self.features(obs, acts)
        self.net.norm.reset()
        self.net.norm.update(x)
        self._uncentre_actions()

    def _uncentre_actions(self) -> None:
        """A control cost's actions are scaled, not centred (`RunningNorm.uncentre`)."""
        if self._split is not None and self.cfg.action_term == "cost":
            self.net.norm.uncentre(self._split)

    # ---------------------------------------------------------------- persistence

    def save(self, path: Path) -> None:
        """Write weights, normaliser, L2 weight, dims and config as one torch file that
        `torch.load(path, weights_only=True)` reads."""
        torch.save(
            {
                "format": FORMAT_VERSION,
                "obs_dim": self.obs_dim,
                "act_dim": self.act_dim,
                "config": dataclasses.asdict(self.cfg),
                "l2_weight": self.l2_weight,
                "output_shift": self.output_shift,
                "output_scale": self.output_scale,
                "state_dict": self.net.state_dict(),
            },
            path,
        )

    def load_state(self, path: Path) -> None:
        """Load a file written by `save` into this ensemble, in place (bound methods such as
        `mean_reward` handed to PPO see the new weights).

        Raises ValueError when the file's format, dims or network shape differ from this
        ensemble's.
        """
        payload = _read(path)
        if (payload["obs_dim"], payload["act_dim"]) != (self.obs_dim, self.act_dim):
            raise ValueError(
                f"{path} holds an ensemble over obs {payload['obs_dim']} / act "
                f"{payload['act_dim']}, this one is {self.obs_dim} / {self.act_dim}"
            )
        try:
            self.net.load_state_dict(payload["state_dict"])
        except RuntimeError as error:
            raise ValueError(f"{path} does not fit this ensemble: {error}") from error
        self.l2_weight = float(payload["l2_weight"])
        # files written before outputs were standardised hold neither: the identity
        self.output_shift = payload.get("output_shift", torch.zeros(self.size, 1))
        self.output_scale = payload.get("output_scale", torch.ones(self.size, 1))

    @classmethod
    def load(cls, path: Path) -> "RewardEnsemble":
        """Rebuild an ensemble (config included) from a file written by `save`."""
        payload = _read(path)
        known = {f.name for f in dataclasses.fields(RewardConfig)}
        values: dict[str, Any] = {
            k: tuple(v) if isinstance(v, list) else v
            for k, v in payload["config"].items()
            if k in known
        }
        ensemble = cls(
            payload["obs_dim"],
            payload["act_dim"],
            RewardConfig(**values),
            np.random.default_rng(0),
        )
        ensemble.load_state(path)
        return ensemble


def _read(path: Path) -> dict[str, Any]:
    payload = torch.load(path, weights_only=True)
    if not isinstance(payload, dict) or payload.get("format") != FORMAT_VERSION:
        raise ValueError(f"{path} is not a reward ensemble file (format {FORMAT_VERSION})")
    return payload
