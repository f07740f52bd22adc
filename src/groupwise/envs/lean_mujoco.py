"""Gymnasium's v5 Hopper, Walker2d and HalfCheetah with a leaner `step`, bit for bit the same.

Sampling a round's behaviours is mostly stepping these envs, and a stock v5 step spends about
as long in Python as in MuJoCo (issue 22: Hopper ~100 µs of ``mj_step`` and ~75 µs of Python;
Hopper-v5 evaluates ``is_healthy``, a concatenation and three reductions, twice a step). Each
env here subclasses the stock one and overrides only `step`, which computes every term once,
in the stock order with the stock operations, so observations, rewards, flags, the info dict
(same keys, values and types) and the physics are identical: tested side by side with the
stock env over whole episodes, resets included (tests/unit/envs/test_lean_mujoco.py). Reset,
rendering and everything else are the stock env's.

The step duration ``dt`` is read once, at construction (the stock env recomputes it from the
model every step); nothing in groupwise changes a model's timestep or frame skip afterwards.
"""

from typing import Any

import mujoco
import numpy as np
from gymnasium.envs.mujoco.half_cheetah_v5 import HalfCheetahEnv
from gymnasium.envs.mujoco.hopper_v5 import HopperEnv
from gymnasium.envs.mujoco.mujoco_env import MujocoEnv
from gymnasium.envs.mujoco.walker2d_v5 import Walker2dEnv
from numpy.typing import NDArray

StepReturn = tuple[NDArray[np.float64], np.float64, bool, bool, dict[str, np.float64]]
"""The stock v5 envs' `step` annotation."""


def _simulate(env: MujocoEnv, action: Any, shape: tuple[int], dt: float) -> tuple[Any, Any]:
    """The stock ``do_simulation(action, frame_skip)``; (x position after, x velocity)."""
    if np.shape(action) != shape:
        raise ValueError(f"Action dimension mismatch. Expected {shape}, found {np.shape(action)}")
    data = env.data
    x_before = data.qpos[0]
    data.ctrl[:] = action
    mujoco.mj_step(env.model, data, nstep=env.frame_skip)
    # the stock env computes cacc, cfrc_int and cfrc_ext after every step; so do we
    mujoco.mj_rnePostConstraint(env.model, data)
    x_after = data.qpos[0]
    return x_after, (x_after - x_before) / dt


def _observation(env: MujocoEnv, exclude_x: bool, clip: float | None) -> NDArray[np.float64]:
    """The stock ``_get_obs`` of the three envs: qpos (without x when `exclude_x`) then qvel,
    clipped to ±`clip` where given (Hopper, Walker2d)."""
    data = env.data
    qpos = data.qpos[1:] if exclude_x else data.qpos
    obs = np.concatenate((qpos, data.qvel))
    if clip is not None:
        velocity = obs[len(qpos) :]
        np.clip(velocity, -clip, clip, out=velocity)
    return obs


def _control_cost(weight: float, action: Any) -> Any:
    # the stock ``weight * np.sum(np.square(action))``: np.sum of an array is this reduce;
    # the cost's dtype follows the action's (float32 from most policies)
    return weight * np.add.reduce(np.square(action), axis=None)


def _upright_step(env: "LeanHopperEnv | LeanWalker2dEnv", action: Any) -> StepReturn:
    """The stock v5 `step` of Hopper and Walker2d (the same in both), ``is_healthy`` once:
    the env's own property (Walker2d's gives a NumPy bool, which the info keeps)."""
    x_after, x_velocity = _simulate(env, action, env._lean_shape, env._lean_dt)
    observation = _observation(env, env._exclude_current_positions_from_observation, 10)
    healthy = env.is_healthy
    forward_reward = env._forward_reward_weight * x_velocity
    healthy_reward = healthy * env._healthy_reward
    ctrl_cost = _control_cost(env._ctrl_cost_weight, action)
    reward = forward_reward + healthy_reward - ctrl_cost
    terminated = (not healthy) and env._terminate_when_unhealthy
    info = {
        "x_position": x_after,
        "z_distance_from_origin": env.data.qpos[1] - env.init_qpos[1],
        "x_velocity": x_velocity,
        "reward_forward": forward_reward,
        "reward_ctrl": -ctrl_cost,
        "reward_survive": healthy_reward,
    }
    if env.render_mode == "human":
        env.render()
    return observation, reward, terminated, False, info


class LeanHopperEnv(HopperEnv):
    """Hopper-v5 whose `step` evaluates ``is_healthy`` once (module docstring)."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self._lean_dt = self.dt
        self._lean_shape = (self.model.nu,)

    @property
    def is_healthy(self) -> bool:
        """The stock test, short-circuited: z and angle first, then the state's range."""
        qpos = self.data.qpos
        min_z, max_z = self._healthy_z_range
        min_angle, max_angle = self._healthy_angle_range
        if not (min_z < qpos[1] < max_z and min_angle < qpos[2] < max_angle):
            return False
        state = np.concatenate((qpos, self.data.qvel))[2:]
        min_state, max_state = self._healthy_state_range
        return bool(np.logical_and(min_state < state, state < max_state).all())

    def step(self, action: Any) -> StepReturn:
        return _upright_step(self, action)


class LeanWalker2dEnv(Walker2dEnv):
    """Walker2d-v5 whose `step` evaluates ``is_healthy`` once (module docstring)."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self._lean_dt = self.dt
        self._lean_shape = (self.model.nu,)

    def step(self, action: Any) -> StepReturn:
        return _upright_step(self, action)


class LeanHalfCheetahEnv(HalfCheetahEnv):
    """HalfCheetah-v5 with the lean `step` (module docstring)."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self._lean_dt = self.dt
        self._lean_shape = (self.model.nu,)

    def step(self, action: Any) -> StepReturn:
        x_after, x_velocity = _simulate(self, action, self._lean_shape, self._lean_dt)
        observation = _observation(self, self._exclude_current_positions_from_observation, None)
        forward_reward = self._forward_reward_weight * x_velocity
        ctrl_cost = _control_cost(self._ctrl_cost_weight, action)
        reward = forward_reward - ctrl_cost
        info = {
            "x_position": x_after,
            "x_velocity": x_velocity,
            "reward_forward": forward_reward,
            "reward_ctrl": -ctrl_cost,
        }
        if self.render_mode == "human":
            self.render()
        return observation, reward, False, False, info
