"""A VecEnv wrapper that replaces the env's reward with a learned one (SPEC §3.5).

The true reward keeps flowing: it is put in each step's info as `true_reward`, and a
`VecMonitor` placed *below* this wrapper records true episode returns, which SB3 then logs
as `rollout/ep_rew_mean`.
"""

from collections.abc import Callable

import numpy as np
from stable_baselines3.common.vec_env import VecEnv, VecEnvWrapper
from stable_baselines3.common.vec_env.base_vec_env import VecEnvStepReturn

from groupwise.envs.spaces import encode_actions
from groupwise.types import FloatArray

RewardFn = Callable[[FloatArray, FloatArray], FloatArray]
"""(obs (B, obs_dim), encoded actions (B, act_dim)) -> per-step reward (B,)."""


class LearnedRewardVecEnv(VecEnvWrapper):
    """Rewards each step with `reward_fn(obs_t, act_t)`, obs_t being the obs the action saw."""

    def __init__(self, venv: VecEnv, reward_fn: RewardFn) -> None:
        super().__init__(venv)
        self.reward_fn = reward_fn
        self._obs: np.ndarray | None = None
        self._actions: np.ndarray | None = None

    def reset(self) -> np.ndarray:
        obs = np.asarray(self.venv.reset())  # Box observations only
        self._obs = obs
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions)
        self.venv.step_async(actions)

    def step_wait(self) -> VecEnvStepReturn:
        if self._obs is None or self._actions is None:
            raise RuntimeError("step before reset")
        obs, true_rewards, dones, infos = self.venv.step_wait()
        features = self._obs.reshape(self.num_envs, -1).astype(np.float32)
        acts = encode_actions(self.action_space, self._actions)
        rewards = np.asarray(self.reward_fn(features, acts), dtype=np.float32)
        for info, true_reward in zip(infos, true_rewards, strict=True):
            info.setdefault("true_reward", float(true_reward))
        self._obs = np.asarray(obs)
        return obs, rewards, dones, infos
