"""Fixed-horizon versions of Gymnasium's MuJoCo envs (v5): original rewards, no termination.

Each `make_*` function is a Gymnasium entry point (see `registry.py`, which adds the horizon
through ``max_episode_steps``). What differs from the standard v5 env:

- Hopper, Walker2d: ``terminate_when_unhealthy=False`` — a fall does not end the episode (the
  healthy bonus is still only paid while healthy, as in the original reward).
- HalfCheetah, Reacher: nothing but the horizon (Reacher: 1000 steps instead of 50).
- All: frames default to 240×240, are rendered with `FastMujocoRendering` (Hopper, Walker2d
  and HalfCheetah with a camera tracking the torso; Reacher with Gymnasium's fixed view), and
  the reward is copied into ``info["true_reward"]``.
- Hopper, Walker2d, HalfCheetah: the stock env's `step` computes each term once
  (`lean_mujoco`), bit for bit the same.
"""

from typing import Any

import gymnasium as gym
from gymnasium.envs.mujoco.mujoco_env import MujocoEnv
from gymnasium.envs.mujoco.reacher_v5 import ReacherEnv

from groupwise.envs.lean_mujoco import LeanHalfCheetahEnv, LeanHopperEnv, LeanWalker2dEnv
from groupwise.envs.rendering import DEFAULT_FRAME_SIZE, FastMujocoRendering
from groupwise.envs.true_reward import TrueRewardInfo


def _make(
    env_class: type[MujocoEnv],
    tracked_body: str | None,
    render_mode: str | None,
    width: int,
    height: int,
    **kwargs: Any,
) -> gym.Env[Any, Any]:
    env = env_class(render_mode=render_mode, width=width, height=height, **kwargs)
    return TrueRewardInfo(FastMujocoRendering(env, tracked_body=tracked_body))


def make_hopper(
    render_mode: str | None = None,
    width: int = DEFAULT_FRAME_SIZE[0],
    height: int = DEFAULT_FRAME_SIZE[1],
    **kwargs: Any,
) -> gym.Env[Any, Any]:
    """Hopper-v5 (obs 11, act 3) that keeps going when unhealthy; `kwargs` go to HopperEnv."""
    return _make(
        LeanHopperEnv, "torso", render_mode, width, height, terminate_when_unhealthy=False, **kwargs
    )


def make_walker2d(
    render_mode: str | None = None,
    width: int = DEFAULT_FRAME_SIZE[0],
    height: int = DEFAULT_FRAME_SIZE[1],
    **kwargs: Any,
) -> gym.Env[Any, Any]:
    """Walker2d-v5 (obs 17, act 6) that keeps going when unhealthy; `kwargs` go to Walker2dEnv."""
    return _make(
        LeanWalker2dEnv,
        "torso",
        render_mode,
        width,
        height,
        terminate_when_unhealthy=False,
        **kwargs,
    )


def make_half_cheetah(
    render_mode: str | None = None,
    width: int = DEFAULT_FRAME_SIZE[0],
    height: int = DEFAULT_FRAME_SIZE[1],
    **kwargs: Any,
) -> gym.Env[Any, Any]:
    """HalfCheetah-v5 (obs 17, act 6); `kwargs` go to HalfCheetahEnv."""
    return _make(LeanHalfCheetahEnv, "torso", render_mode, width, height, **kwargs)


def make_reacher(
    render_mode: str | None = None,
    width: int = DEFAULT_FRAME_SIZE[0],
    height: int = DEFAULT_FRAME_SIZE[1],
    **kwargs: Any,
) -> gym.Env[Any, Any]:
    """Reacher-v5 (obs 10, act 2), fixed camera; `kwargs` go to ReacherEnv."""
    return _make(ReacherEnv, None, render_mode, width, height, **kwargs)
