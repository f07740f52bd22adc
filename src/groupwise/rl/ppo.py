"""The thin adapter over Stable-Baselines3 PPO (SPEC §3.5): build, learn, act, save, load.

SB3 is used as it is (no subclassing). Its `set_random_seed` seeds global RNGs; that stays
inside this adapter, and every round reseeds it from the loop's generator, so a resumed run
repeats an uninterrupted one.
"""

import copy
import dataclasses
import logging
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import torch
from stable_baselines3 import PPO
from stable_baselines3.common.logger import Logger
from stable_baselines3.common.policies import ActorCriticPolicy
from stable_baselines3.common.running_mean_std import RunningMeanStd
from stable_baselines3.common.utils import configure_logger
from stable_baselines3.common.vec_env import DummyVecEnv, VecEnv, VecMonitor, VecNormalize

from groupwise.config import PPOConfig
from groupwise.rl.callbacks import ProgressCallback, ProgressFn
from groupwise.rl.learned_reward import LearnedRewardVecEnv, RewardFn
from groupwise.rl.rollout import EnvFactory
from groupwise.types import FloatArray

log = logging.getLogger(__name__)

POLICY_FILE = "policy.zip"
NORMALISER_FILE = "vecnormalize.npz"


class PPOAgent:
    """A PPO learner on `n_envs` copies of an env, rewarded by `reward_fn` or the true reward.

    With `reward_fn=None` PPO trains on the env's own reward (the upper-bound baseline).
    """

    def __init__(
        self,
        make_env: EnvFactory,
        cfg: PPOConfig,
        seed: int,
        reward_fn: RewardFn | None = None,
        log_dir: Path | None = None,
    ) -> None:
        self.cfg = cfg
        self.step_norm: StandardisedReward | None = None
        if reward_fn is not None and cfg.standardise_reward:
            reward_fn = self.step_norm = StandardisedReward(reward_fn)
        self.venv = _training_env(make_env, cfg, reward_fn)
        self.model = PPO(
            "MlpPolicy",
            self.venv,
            learning_rate=cfg.learning_rate,
            n_steps=cfg.n_steps,
            batch_size=cfg.batch_size,
            n_epochs=cfg.n_epochs,
            gamma=cfg.gamma,
            gae_lambda=cfg.gae_lambda,
            clip_range=cfg.clip_range,
            ent_coef=cfg.ent_coef,
            policy_kwargs={"net_arch": list(cfg.net_arch)},
            tensorboard_log=str(log_dir) if log_dir is not None and cfg.tensorboard else None,
            seed=seed,
            device="cpu",
            verbose=0,
        )
        self._logger: Logger | None = None

    @property
    def num_timesteps(self) -> int:
        return int(self.model.num_timesteps)

    @property
    def rollout_steps(self) -> int:
        """Env steps of one rollout (n_envs × n_steps): `learn` trains in whole rollouts."""
        return self.cfg.n_envs * self.cfg.n_steps

    def learn(
        self,
        steps: int,
        seed: int | None,
        report: ProgressFn | None = None,
        stop: Callable[[], bool] | None = None,
    ) -> None:
        """Train for at least `steps` env steps (whole rollouts), fewer when `stop` ends it.

        With a `seed` the call reseeds SB3 and starts fresh episodes, so the result depends
        only on the saved state and `seed` (which makes `--resume` exact); with None it
        continues the episodes in flight and SB3's random state (continuous training's
        later slices of one round, `groupwise.run.continuous`).

        `stop` is asked at every step of a rollout (`ProgressCallback`): when it says True
        the rollout in progress is dropped untrained and the step count goes back to the
        rollouts trained, so it stays a whole number of rollouts (the envs' episodes have
        moved on by the dropped steps; `rl.recording` keeps them, played by the policy now).
        """
        if steps <= 0:
            return
        if seed is not None:
            self.model.set_random_seed(seed)
            if self.cfg.reset_reward_norm:
                self._normaliser().ret_rms = RunningMeanStd(shape=())
                if self.step_norm is not None:
                    self.step_norm.stats = RunningMeanStd(shape=())
            self.model.set_env(self.venv, force_reset=True)
        self.model.set_logger(self.logger())
        callback = ProgressCallback(steps, report, stop)
        before = self.model.num_timesteps
        self.model.learn(
            total_timesteps=steps,
            callback=callback,
            reset_num_timesteps=False,
            tb_log_name="ppo",
        )
        if callback.stopped:
            self.model.num_timesteps = before + callback.rollouts * self.rollout_steps

    def pretrain(
        self,
        reward_fn: RewardFn,
        steps: int,
        seed: int,
        report: ProgressFn | None = None,
        then_log_std: float | None = None,
    ) -> None:
        """Train `steps` env steps (whole rollouts, seeded as `learn`) on `reward_fn` in
        place of the learned reward (unsupervised pre-training, `groupwise.run.pretrain`),
        then forget what only that reward taught: the running return sd and the value
        function, as PEBBLE resets its critic after pre-training (B-Pref, train_PEBBLE.py).
        The policy and the observation statistics are kept; with `then_log_std` its action
        noise is set to σ = exp(`then_log_std`) (`TrainingConfig.teach_log_std`), its mean
        action unchanged.

        Raises:
            ValueError: the agent trains on the env's own reward (no learned reward to swap),
                or `then_log_std` is given for a policy without a Gaussian action noise.
        """
        if then_log_std is not None and not hasattr(self.model.policy, "log_std"):
            raise ValueError("teach_log_std needs continuous actions (a Gaussian policy)")
        rewarded = self.venv.venv if isinstance(self.venv, VecNormalize) else None
        if not isinstance(rewarded, LearnedRewardVecEnv):
            raise ValueError("pre-training needs an agent on a learned reward")
        own = rewarded.reward_fn
        rewarded.reward_fn = reward_fn
        try:
            self.learn(steps, seed, report)
        finally:
            rewarded.reward_fn = own
        self._normaliser().ret_rms = RunningMeanStd(shape=())
        policy = self.model.policy
        heads = ((policy.mlp_extractor.value_net, np.sqrt(2)), (policy.value_net, 1.0))
        for module, gain in heads:  # SB3's own initialisation (seeded by `learn`)
            module.apply(partial(policy.init_weights, gain=gain))
        if then_log_std is not None:
            with torch.no_grad():
                policy.log_std.fill_(then_log_std)

    def act(self, obs: FloatArray, rng: np.random.Generator, deterministic: bool) -> np.ndarray:
        """Actions for raw observations (B, *obs_shape) (`policy_actions`)."""
        normalised = self._normaliser().normalize_obs(np.asarray(obs, dtype=np.float32))
        assert isinstance(normalised, np.ndarray)  # Box observations
        return policy_actions(self.model.policy, normalised, rng, deterministic)

    def snapshot(
        self, deterministic: bool = False, state: "PolicyState | None" = None
    ) -> "PolicySnapshot":
        """A frozen, picklable copy of this agent's policy as it acts now (or as it acted
        in `state`): another process can act with it (the worker's curve evaluations) while
        this one trains on."""
        norm = self._normaliser()
        state = self.policy_state() if state is None else state
        source = self.model.policy
        with torch.random.fork_rng(devices=[]):  # its initial weights draw from torch's RNG
            network = type(source)(**source._get_constructor_parameters())
        network.load_state_dict(state.network)
        network.set_training_mode(False)
        return PolicySnapshot(
            network,
            state.obs_mean.copy() if norm.norm_obs else None,
            state.obs_var.copy() if norm.norm_obs else None,
            norm.epsilon,
            norm.clip_obs,
            deterministic,
        )

    def policy_state(self) -> "PolicyState":
        """A copy of what PPO acts and learns with now: its networks, their optimiser and
        the observation statistics; not the step count, which goes on counting."""
        obs_rms, _ = self._running_stats()
        policy = self.model.policy
        return PolicyState(
            copy.deepcopy(policy.state_dict()),
            copy.deepcopy(policy.optimizer.state_dict()),
            obs_rms.mean.copy(),
            obs_rms.var.copy(),
            float(obs_rms.count),
        )

    def load_policy_state(self, state: "PolicyState") -> None:
        """Act and learn from `state` (a `policy_state`) on."""
        policy = self.model.policy
        policy.load_state_dict(state.network)
        policy.optimizer.load_state_dict(copy.deepcopy(state.optimizer))
        obs_rms, _ = self._running_stats()
        obs_rms.mean, obs_rms.var = state.obs_mean.copy(), state.obs_var.copy()
        obs_rms.count = state.obs_count

    def policy(self, deterministic: bool = False) -> "AgentPolicy":
        """This agent as a `Policy` (stochastic for sampling behaviours, greedy for evaluation)."""
        return AgentPolicy(self, deterministic)

    def save(self, directory: Path) -> None:
        directory.mkdir(parents=True, exist_ok=True)
        self.model.save(directory / POLICY_FILE)
        obs_rms, ret_rms = self._running_stats()
        arrays: dict[str, Any] = {
            "obs_mean": obs_rms.mean,
            "obs_var": obs_rms.var,
            "obs_count": obs_rms.count,
            "ret_mean": ret_rms.mean,
            "ret_var": ret_rms.var,
            "ret_count": ret_rms.count,
        }
        if self.step_norm is not None:
            stats = self.step_norm.stats
            arrays |= {"step_mean": stats.mean, "step_var": stats.var, "step_count": stats.count}
        np.savez(directory / NORMALISER_FILE, **arrays)

    def load(self, directory: Path) -> None:
        """Restore the policy, its optimiser, step count and normaliser saved by `save`."""
        tensorboard_log = self.model.tensorboard_log
        self.model = PPO.load(directory / POLICY_FILE, env=self.venv, device="cpu")
        self.model.tensorboard_log = tensorboard_log
        obs_rms, ret_rms = self._running_stats()
        with np.load(directory / NORMALISER_FILE) as data:
            obs_rms.mean, obs_rms.var = data["obs_mean"], data["obs_var"]
            obs_rms.count = float(data["obs_count"])
            ret_rms.mean, ret_rms.var = data["ret_mean"], data["ret_var"]
            ret_rms.count = float(data["ret_count"])
            if self.step_norm is not None and "step_mean" in data:
                stats = self.step_norm.stats
                stats.mean, stats.var = data["step_mean"], data["step_var"]
                stats.count = float(data["step_count"])

    def logger(self) -> Logger:
        """The one logger of every `learn` call: TensorBoard's ``ppo_0`` folder under the
        agent's log directory, else none. Left to SB3, each call would open a new
        TensorBoard writer (a thread and an events file, never closed: thousands over a
        continuous session's slices) or, without TensorBoard, a /tmp/SB3-<time> folder."""
        if self._logger is None:
            folder = self.model.tensorboard_log
            self._logger = (
                Logger(folder=None, output_formats=[])
                if folder is None
                else configure_logger(0, folder, "ppo", reset_num_timesteps=False)
            )
        return self._logger

    def close(self) -> None:
        if self._logger is not None:
            self._logger.close()
        self.venv.close()

    def _normaliser(self) -> VecNormalize:
        assert isinstance(self.venv, VecNormalize)
        return self.venv

    def _running_stats(self) -> tuple[RunningMeanStd, RunningMeanStd]:
        """The observation and return statistics (Box observations only)."""
        norm = self._normaliser()
        assert isinstance(norm.obs_rms, RunningMeanStd)
        return norm.obs_rms, norm.ret_rms


class StandardisedReward:
    """`reward_fn`'s rewards centred and scaled by their running mean and sd over every
    step it has rewarded (`PPOConfig.standardise_reward`; imitation's `NormalizedRewardNet`
    with a `RunningNorm` output layer). The statistics include the batch being rewarded,
    and are never reset unless `PPOConfig.reset_reward_norm` asks it.

    Why: the Bradley–Terry reward's offset is not identified by preferences, and an offset
    that is large against the reward's spread inflates the running return std that
    `VecNormalize` divides by, so PPO sees a flatter reward. The default since issue 41, in
    place of the return scaling (docs/results/peer: Hopper-v4 and Walker2d-v4 at SPEC noise).
    """

    def __init__(self, reward_fn: RewardFn, epsilon: float = 1e-8) -> None:
        self.reward_fn = reward_fn
        self.epsilon = epsilon
        self.stats = RunningMeanStd(shape=())

    def __call__(self, obs: FloatArray, acts: FloatArray) -> FloatArray:
        rewards = np.asarray(self.reward_fn(obs, acts), dtype=np.float64)
        self.stats.update(rewards)
        scaled = (rewards - self.stats.mean) / np.sqrt(self.stats.var + self.epsilon)
        return scaled.astype(np.float32)


def policy_actions(
    network: ActorCriticPolicy,
    normalised: FloatArray,
    rng: np.random.Generator,
    deterministic: bool,
) -> np.ndarray:
    """Actions of an SB3 actor-critic for normalised observations (B, *obs_shape).

    Stochastic actions are drawn from the policy's distribution with `rng` (not torch's
    global generator), greedy ones are its mode; Box actions are clipped to the space
    as SB3's `predict` does.
    """
    with torch.no_grad():
        obs_tensor = torch.as_tensor(normalised, dtype=torch.float32)
        dist = network.get_distribution(obs_tensor).distribution
    if isinstance(dist, torch.distributions.Categorical):
        probs = dist.probs.numpy()
        if deterministic:
            return probs.argmax(axis=1)
        draws = rng.random((probs.shape[0], 1))
        return np.minimum((draws > probs.cumsum(axis=1)).sum(axis=1), probs.shape[1] - 1)
    if isinstance(dist, torch.distributions.Normal):
        mean = dist.mean.numpy()
        actions = (
            mean if deterministic else mean + dist.stddev.numpy() * rng.standard_normal(mean.shape)
        )
        space = network.action_space
        assert isinstance(space, gym.spaces.Box)
        return np.clip(actions, space.low, space.high).astype(space.dtype)
    raise TypeError(f"unsupported policy distribution {type(dist).__name__}")


@dataclass(frozen=True, eq=False)
class PolicyState:
    """What `PPOAgent.policy_state` copies: enough to act and to learn on from there."""

    network: dict[str, Any]
    """The policy and value networks' `state_dict`."""
    optimizer: dict[str, Any]
    obs_mean: np.ndarray
    obs_var: np.ndarray
    obs_count: float

    def save(self, path: Path) -> None:
        fields = dataclasses.asdict(self)
        fields["obs_mean"] = torch.from_numpy(self.obs_mean)
        fields["obs_var"] = torch.from_numpy(self.obs_var)
        torch.save(fields, path)

    @classmethod
    def load(cls, path: Path) -> "PolicyState":
        fields = torch.load(path, weights_only=True)
        fields["obs_mean"] = fields["obs_mean"].numpy()
        fields["obs_var"] = fields["obs_var"].numpy()
        return cls(**fields)


@dataclass(frozen=True)
class PolicySnapshot:
    """A `Policy` frozen from a `PPOAgent` (`PPOAgent.snapshot`): a copy of its network and
    of its observation normalisation (SB3's `VecNormalize.normalize_obs`: none when
    `obs_mean` is None), acting exactly as the agent did when it was taken."""

    network: ActorCriticPolicy
    obs_mean: np.ndarray | None
    obs_var: np.ndarray | None
    epsilon: float
    clip_obs: float
    deterministic: bool

    def act(self, obs: FloatArray, rng: np.random.Generator) -> np.ndarray:
        normalised = np.asarray(obs, dtype=np.float32)
        if self.obs_mean is not None and self.obs_var is not None:
            scaled = (normalised - self.obs_mean) / np.sqrt(self.obs_var + self.epsilon)
            normalised = np.clip(scaled, -self.clip_obs, self.clip_obs).astype(np.float32)
        return policy_actions(self.network, normalised, rng, self.deterministic)


class AgentPolicy:
    """Adapts `PPOAgent.act` to the `Policy` interface."""

    def __init__(self, agent: PPOAgent, deterministic: bool) -> None:
        self.agent = agent
        self.deterministic = deterministic

    def act(self, obs: FloatArray, rng: np.random.Generator) -> np.ndarray:
        return self.agent.act(obs, rng, self.deterministic)


def _training_env(make_env: EnvFactory, cfg: PPOConfig, reward_fn: RewardFn | None) -> VecEnv:
    # One process: on 2 cores the per-step IPC of SubprocVecEnv costs more than it saves
    # for these small envs (see benchmarks/ppo_throughput.py).
    venv: VecEnv = VecMonitor(DummyVecEnv([make_env] * cfg.n_envs))
    if reward_fn is not None:
        venv = LearnedRewardVecEnv(venv, reward_fn)
    standardised = reward_fn is not None and cfg.standardise_reward  # scaled per step already
    return VecNormalize(
        venv,
        norm_obs=cfg.normalize_obs,
        norm_reward=cfg.normalize_reward and not standardised,
        gamma=cfg.gamma,
    )
