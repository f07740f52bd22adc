"""Fixed-horizon envs for RLHF (SPEC §2): registrations, GridWorld, dense MountainCar, rendering.

Importing this package registers the ``groupwise/*-v0`` ids with Gymnasium (idempotently).
`make_env` also makes any other Gymnasium env, by id or as ``"module:Env-v0"``.
"""

from groupwise.envs.registry import (
    ENVS,
    NAMESPACE,
    EnvEntry,
    horizon,
    make_env,
    make_standard_env,
    register_envs,
    resolve_id,
)
from groupwise.envs.rendering import DEFAULT_FRAME_SIZE, RenderingUnavailableError
from groupwise.envs.true_reward import TRUE_REWARD_KEY

register_envs()

__all__ = [
    "DEFAULT_FRAME_SIZE",
    "ENVS",
    "NAMESPACE",
    "TRUE_REWARD_KEY",
    "EnvEntry",
    "RenderingUnavailableError",
    "horizon",
    "make_env",
    "make_standard_env",
    "register_envs",
    "resolve_id",
]
