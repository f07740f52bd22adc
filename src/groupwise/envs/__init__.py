"""Fixed-horizon envs for RLHF (SPEC §2): registrations, GridWorld, dense MountainCar, rendering,
and the case studies' reward-free target envs (`targets`).

Importing this package registers the ``groupwise/*-v0`` ids with Gymnasium (idempotently).
`make_env` also makes any other Gymnasium env, by id or as ``"module:Env-v0"``.
"""

from groupwise.envs.body_state import BodyState
from groupwise.envs.registry import (
    ENVS,
    NAMESPACE,
    TARGET_ENVS,
    EnvEntry,
    env_entry,
    horizon,
    make_env,
    make_standard_env,
    register_envs,
    resolve_id,
)
from groupwise.envs.rendering import DEFAULT_FRAME_SIZE, RenderingUnavailableError
from groupwise.envs.targets import TARGET_SCORE_KEY, TARGET_TOTAL_KEY, TARGETS, Target
from groupwise.envs.true_reward import TRUE_REWARD_KEY

register_envs()

__all__ = [
    "DEFAULT_FRAME_SIZE",
    "ENVS",
    "NAMESPACE",
    "TARGETS",
    "TARGET_ENVS",
    "TARGET_SCORE_KEY",
    "TARGET_TOTAL_KEY",
    "TRUE_REWARD_KEY",
    "BodyState",
    "EnvEntry",
    "RenderingUnavailableError",
    "Target",
    "env_entry",
    "horizon",
    "make_env",
    "make_standard_env",
    "register_envs",
    "resolve_id",
]
