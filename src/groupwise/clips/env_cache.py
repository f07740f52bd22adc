"""This process's rendering envs, one per frame settings: a render process renders many clip
jobs and recipes (`render_jobs`, `recipe`), each with the env it made for those settings
first."""

import time
from typing import Any

import gymnasium as gym

from groupwise.clips.replay import FrameSettings, make_render_env

_ENVS: dict[FrameSettings, gym.Env[Any, Any]] = {}
"""This process's rendering envs, one per settings (a worker renders many jobs)."""


def cached_env(settings: FrameSettings) -> gym.Env[Any, Any]:
    """This process's rendering env for `settings`, made on first use and kept."""
    env = _ENVS.get(settings)
    if env is None:
        env = _ENVS[settings] = make_render_env(settings)
    return env


def warm_up(settings: FrameSettings) -> float:
    """Make (and cache) this worker's env and render one frame; returns the seconds it took."""
    start = time.perf_counter()
    env = cached_env(settings)
    env.reset(seed=0)
    env.render()
    return time.perf_counter() - start
