"""MountainCarContinuous with a dense reward and no termination at the goal.

The dynamics are Gymnasium's ``MountainCarContinuous-v0`` unchanged (including the inelastic
left wall and the clamp at x = 0.6, where the car may sit once past the goal). Only the
reward and the end of the episode differ; the horizon (250 steps) comes from the registration.
"""

from typing import Any

import numpy as np
from gymnasium.envs.classic_control.continuous_mountain_car import Continuous_MountainCarEnv

from groupwise.envs.rendering import DEFAULT_FRAME_SIZE, use_headless_sdl
from groupwise.envs.true_reward import TRUE_REWARD_KEY

GOAL_POSITION = 0.45
"""x at or past which (with v ≥ 0) the goal bonus is paid, as in Gymnasium."""


def dense_reward(position: float, velocity: float, action: float) -> float:
    """Per-step reward of the dense MountainCar, from the state *after* the step.

    ``20·|v| − 0.1 + |x + 0.5| − 0.1 + 100·[x ≥ 0.45 and v ≥ 0] − 0.1·a²`` where `a` is the
    action as given (Gymnasium penalises the unclipped action too).
    """
    at_goal = position >= GOAL_POSITION and velocity >= 0.0
    return (
        20.0 * abs(velocity)
        - 0.1
        + abs(position + 0.5)
        - 0.1
        + (100.0 if at_goal else 0.0)
        - 0.1 * action**2
    )


class DenseMountainCarEnv(Continuous_MountainCarEnv):
    """MountainCarContinuous (obs: position, velocity; act: force in [−1, 1]) with
    `dense_reward`, never terminating; the reward is also in ``info["true_reward"]``.

    Rendering uses Gymnasium's pygame renderer at `width`×`height` with SDL's dummy video
    driver for offscreen modes, so it never opens a window or needs an X server.
    """

    def __init__(
        self,
        render_mode: str | None = None,
        width: int = DEFAULT_FRAME_SIZE[0],
        height: int = DEFAULT_FRAME_SIZE[1],
    ) -> None:
        super().__init__(render_mode=render_mode, goal_velocity=0.0)
        self.screen_width = width
        self.screen_height = height

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Advance Gymnasium's dynamics one step; terminated and truncated are always False."""
        obs, _, _, _, info = super().step(action)
        reward = dense_reward(float(obs[0]), float(obs[1]), float(np.asarray(action).flat[0]))
        info[TRUE_REWARD_KEY] = reward
        return obs, reward, False, False, info

    def render(self) -> Any:
        """A (height, width, 3) uint8 frame in "rgb_array" mode (see the class docstring)."""
        if self.render_mode != "human":
            use_headless_sdl()
        return super().render()
