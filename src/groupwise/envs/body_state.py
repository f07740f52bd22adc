"""What a target score reads of a planar MuJoCo robot's state (Hopper, HalfCheetah, Walker2d).

The three robots move in the x–z plane: ``qpos`` is (rootx, rootz, rooty, joint angles …),
x forward, z up. ``rooty`` is the torso's pitch in radians, positive when the torso's top
tips forward (+x) and its front dips (checked in tests/unit/envs/test_targets.py); MuJoCo
never wraps a hinge angle, so it counts whole turns.
"""

from collections.abc import Mapping
from dataclasses import dataclass

import mujoco
import numpy as np
from gymnasium.envs.mujoco.mujoco_env import MujocoEnv

from groupwise.types import FloatArray

ROBOT_BODY = 1
"""Body id of the robot's root (the torso): its subtree is the whole robot."""


@dataclass(frozen=True)
class BodyState:
    """One instant of a planar robot, as the target scores read it."""

    time: float
    """Simulation time, s."""
    qpos: FloatArray  # (nq,) rootx, rootz, rooty (pitch, rad), joint angles (rad)
    qvel: FloatArray  # (nv,)
    com_height: float
    """Height of the whole robot's centre of mass above the floor, m."""
    bottoms: Mapping[str, float]
    """Lowest point of each capsule geom above the floor, m, by geom name (about 0 or a few
    mm below when the geom rests on the floor)."""

    @property
    def pitch(self) -> float:
        """Torso pitch, rad, positive when the top tips forward; never wrapped."""
        return float(self.qpos[2])

    @classmethod
    def read(cls, env: MujocoEnv) -> "BodyState":
        """The current state of `env` (after a step, a reset or ``set_state``, all of which
        update the positions this reads); `StateReader` reads many states faster."""
        return StateReader(env)()


class StateReader:
    """Reads `BodyState`s of one env, its capsules looked up once (~10 µs a state)."""

    def __init__(self, env: MujocoEnv) -> None:
        model = env.model
        self._data = env.data
        self._capsules = np.flatnonzero(model.geom_type == mujoco.mjtGeom.mjGEOM_CAPSULE)
        self._names = [model.geom(int(g)).name for g in self._capsules]
        # a capsule's axis is its local z; size = (radius, half length)
        self._radius = model.geom_size[self._capsules, 0].copy()
        self._half_length = model.geom_size[self._capsules, 1].copy()

    def __call__(self) -> BodyState:
        data = self._data
        axis_z = data.geom_xmat[self._capsules, 8]
        lowest = data.geom_xpos[self._capsules, 2] - np.abs(axis_z) * self._half_length
        return BodyState(
            time=float(data.time),
            qpos=data.qpos.copy(),
            qvel=data.qvel.copy(),
            com_height=float(data.subtree_com[ROBOT_BODY, 2]),
            bottoms=dict(zip(self._names, (lowest - self._radius).tolist(), strict=True)),
        )
