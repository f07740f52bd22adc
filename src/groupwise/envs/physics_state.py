"""Snapshots of a MuJoCo env's physics: render a window of an episode without replaying it.

A clip is reproduced by replaying its episode's actions from the reset seed
(`groupwise.clips.replay`); for a window late in a long episode most of that replay is
stepping towards the window. MuJoCo's integration state (``mjSTATE_INTEGRATION``: time,
positions, velocities, actuator activations, warm start, controls and applied forces) is
everything the next step depends on, so restoring the state captured before step t − 1 and
taking step t − 1 again leaves the simulation, and so the frame of step t, exactly as the
replay from the reset leaves it (tested bit for bit on Hopper, Walker2d, HalfCheetah and
Reacher, issue 22). The sampler captures a few such snapshots per window
(`rl.rollout.sample_episodes_for_windows`); other envs (GridWorld, classic control) have
none and are replayed.
"""

from typing import Any

import gymnasium as gym
import numpy as np

from groupwise.types import FloatArray


def _mujoco_parts(env: gym.Env[Any, Any]) -> tuple[Any, Any, Any] | None:
    """(mujoco module, model, data) of a MuJoCo env, None for any other env."""
    base = env.unwrapped
    model, data = getattr(base, "model", None), getattr(base, "data", None)
    if model is None or data is None:
        return None
    import mujoco  # only MuJoCo envs get here (keeps the import off other callers)

    if not isinstance(model, mujoco.MjModel) or not isinstance(data, mujoco.MjData):
        return None
    return mujoco, model, data


def physics_state(env: gym.Env[Any, Any]) -> FloatArray | None:
    """The env's MuJoCo integration state (S,) float64 now, or None for a non-MuJoCo env."""
    parts = _mujoco_parts(env)
    if parts is None:
        return None
    mujoco, model, data = parts
    spec = mujoco.mjtState.mjSTATE_INTEGRATION
    state = np.empty(mujoco.mj_stateSize(model, spec), dtype=np.float64)
    mujoco.mj_getState(model, data, state, spec)
    return state


def restore_physics_state(env: gym.Env[Any, Any], state: FloatArray) -> None:
    """Set the env's MuJoCo integration state to `state` (from `physics_state` of an env made
    the same way). Observations and frames follow from the next step on.

    Raises:
        ValueError: not a MuJoCo env, or a state of another size (another model).
    """
    parts = _mujoco_parts(env)
    if parts is None:
        raise ValueError(f"{env.unwrapped} is not a MuJoCo env: it has no physics state")
    mujoco, model, data = parts
    spec = mujoco.mjtState.mjSTATE_INTEGRATION
    state = np.ascontiguousarray(state, dtype=np.float64)
    size = mujoco.mj_stateSize(model, spec)
    if state.shape != (size,):
        raise ValueError(f"a physics state of shape {state.shape} for a model of {size} values")
    mujoco.mj_setState(model, data, state, spec)


def show_physics_state(env: gym.Env[Any, Any], state: FloatArray) -> None:
    """Set the env's MuJoCo integration state to `state` and compute its positions
    (``mj_forward``), so that the next frame rendered shows that state without a step
    (a recorded dataset's clips, `groupwise.envs.datasets`).

    Raises:
        ValueError: as `restore_physics_state`.
    """
    restore_physics_state(env, state)
    parts = _mujoco_parts(env)
    assert parts is not None
    mujoco, model, data = parts
    mujoco.mj_forward(model, data)
