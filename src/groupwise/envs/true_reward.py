"""Keeping the env's own reward in ``info["true_reward"]`` for evaluation and simulated users."""

from typing import Any, SupportsFloat

import gymnasium as gym

TRUE_REWARD_KEY = "true_reward"
"""The `info` key under which every groupwise env reports its true per-step reward."""


class TrueRewardInfo(gym.Wrapper[Any, Any, Any, Any]):
    """Copies each step's reward into ``info["true_reward"]`` (a float); nothing else changes.

    Wrappers further out (e.g. one that substitutes a learned reward) may replace the reward,
    but the true reward stays in `info`.
    """

    def step(self, action: Any) -> tuple[Any, SupportsFloat, bool, bool, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(action)
        info[TRUE_REWARD_KEY] = float(reward)
        return obs, reward, terminated, truncated, info
