"""The DeepMind Control suite through Shimmy: ``dm_control/<domain>-<task>-v0`` (issue 42).

Shimmy (the optional extra ``groupwise[dmc]``, ``shimmy[dm-control]``) registers the suite's
tasks with Gymnasium when it is imported; `make_env` imports it for any id in the
``dm_control/`` namespace, and adapts what it makes in three ways:

- **Horizon.** dm_control ends an episode itself after its task's time limit (the suite's
  20-25 s: 1,000 control steps for every task of the suite), not through a Gymnasium
  ``TimeLimit``, so the registration has no ``max_episode_steps``. `suite_step_limit` reads
  the limit from the dm_control environment and `adapt` adds a ``TimeLimit`` of exactly
  that many steps, which ends each episode on the same step dm_control does and tells the
  rest of groupwise (`envs.horizon`, the rollouts) the fixed horizon.
- **Observations.** The suite observes a dict; `envs.flatten` makes it one vector.
- **Frames.** Clips are rendered offscreen by dm_control's own renderer, through the GL
  backend `envs.rendering.ensure_gl_backend` chose (dm_control reads ``MUJOCO_GL`` once,
  when it is imported, so the choice is made before Shimmy is imported), from the task's
  first camera (every suite domain's camera 0 follows the body, as dm_control's own pixel
  wrapper uses it) without shadows, reflections, skybox or multisampling: Walker-walk at
  240 × 240 with EGL on a CPU took 76 ms a frame with them and 27 ms without.
"""

import math
from typing import Any

import gymnasium as gym

from groupwise.envs.mujoco_log import log_mujoco_warnings
from groupwise.envs.rendering import RenderingUnavailableError, ensure_gl_backend

NAMESPACE = "dm_control"
"""Gymnasium namespace of the suite's ids."""

MODULE = "shimmy"
"""The module whose import registers the ``dm_control/`` ids."""

EXTRA = "dmc"
"""groupwise's optional extra that installs it (``pip install 'groupwise[dmc]'``)."""

FAST_RENDER_FLAGS: dict[str, bool] = {"shadow": False, "reflection": False, "skybox": False}
"""dm_control's ``render_flag_overrides`` for clip frames (module docstring)."""


def is_dmc_id(gym_id: str) -> bool:
    """Whether a Gymnasium id is one of the suite's (``dm_control/…``)."""
    return gym_id.partition("/")[0] == NAMESPACE


def prepare_import() -> None:
    """Choose MuJoCo's offscreen GL backend before dm_control is imported (it reads
    ``MUJOCO_GL`` then, and without it tries GLFW, which needs a display). With no backend
    at all nothing is chosen: training needs no frames, and rendering fails later with the
    packages to install."""
    try:
        ensure_gl_backend()
    except RenderingUnavailableError:
        pass


def after_import() -> None:
    """Take MuJoCo's warnings back from dm_control, which routes every one to absl's log at
    import (cheetah.xml's "settotalmass is deprecated" then printed once per env made: eleven
    lines for a smoke-sized study cell), to `log_mujoco_warnings`: each text once."""
    import mujoco

    mujoco.set_mju_user_warning(None)
    log_mujoco_warnings()


def make_kwargs(render_mode: str | None, kwargs: dict[str, Any]) -> dict[str, Any]:
    """`gymnasium.make`'s keyword arguments for a suite id from `make_env`'s: ``width`` and
    ``height`` (and ``camera_id``) go to dm_control's renderer through Shimmy's
    ``render_kwargs``, with `FAST_RENDER_FLAGS` for ``rgb_array`` frames."""
    rest = dict(kwargs)
    render = dict(rest.pop("render_kwargs", None) or {})
    for key in ("width", "height", "camera_id"):
        if key in rest:
            render[key] = rest.pop(key)
    if render_mode == "rgb_array":
        render.setdefault("render_flag_overrides", dict(FAST_RENDER_FLAGS))
    return {**rest, "render_kwargs": render} if render else rest


def suite_step_limit(env: gym.Env[Any, Any]) -> int | None:
    """Control steps after which dm_control ends an episode of `env` (a Shimmy env), or None
    when its task has no time limit (dm_control's LQR tasks) or it is no dm_control env.

    A ``control.Environment`` (the suite) stops once its step count reaches
    ``time_limit / control_timestep``, i.e. after the ceiling of that many steps; a
    ``composer.Environment`` once physics time reaches its time limit.
    """
    inner = getattr(env.unwrapped, "_env", None)  # Shimmy keeps the dm_control env here
    # dm_control exposes neither limit publicly; both are set once, in its constructor.
    limit = getattr(inner, "_step_limit", None)
    if limit is None and inner is not None:
        seconds = getattr(inner, "_time_limit", None)
        if seconds is not None:
            limit = seconds / inner.control_timestep()
    if limit is None or not math.isfinite(limit):
        return None
    return math.ceil(limit - 1e-9)


def adapt(env: gym.Env[Any, Any]) -> gym.Env[Any, Any]:
    """A suite env with its time limit as a ``TimeLimit`` (module docstring) and, rendered
    offscreen, its camera and model set for fast frames."""
    inner = getattr(env.unwrapped, "_env", None)
    physics = getattr(inner, "physics", None)
    if physics is not None and env.render_mode == "rgb_array":
        physics.model.vis.quality.offsamples = 0  # before dm_control's first frame makes the GL
        render = env.unwrapped.render_kwargs  # type: ignore[attr-defined]  # Shimmy's own
        if physics.model.ncam > 0:
            render.setdefault("camera_id", 0)
    steps = suite_step_limit(env)
    if steps is None or (env.spec is not None and env.spec.max_episode_steps is not None):
        return env
    return gym.wrappers.TimeLimit(env, max_episode_steps=steps)
