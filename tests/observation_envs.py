"""Toy envs with structured and unusable observation spaces; importing this module registers
them, as a user's own env package would (name them ``tests.observation_envs:<Id>``).

Each observes a deterministic function of its reset seed and step count, so that runs can be
compared value for value. `DictObs-v0` builds its observation dict by iterating over a set of
keys, whose order depends on the process's hash seed: a flattening that followed the dict's
order, not the documented sorted one, would give different vectors in different processes.
"""

from typing import Any, ClassVar

import gymnasium as gym
import numpy as np

MODULE = __name__

SHAPES = {"velocity": (3,), "position": (2,), "height": ()}
"""`DictObs-v0`'s entries; flattened: height (1), position (2), velocity (3)."""


class _Toy(gym.Env[Any, np.ndarray]):
    """Actions in [-1, 1]²; the reward is the first action; never terminates."""

    action_space = gym.spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array"], "render_fps": 30}

    def __init__(self, render_mode: str | None = None) -> None:
        self.render_mode = render_mode
        self._base = 0.0
        self._t = 0

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> Any:
        super().reset(seed=seed)
        self._base = float(self.np_random.uniform(-1.0, 1.0))
        self._t = 0
        return self._observe(), {}

    def step(self, action: np.ndarray) -> Any:
        self._t += 1
        return self._observe(), float(np.asarray(action)[0]), False, False, {}

    def render(self) -> np.ndarray:
        return np.full((16, 16, 3), self._t % 256, dtype=np.uint8)

    def _values(self, shape: tuple[int, ...], offset: float) -> np.ndarray:
        count = int(np.prod(shape))
        return (self._base + offset + 0.01 * self._t + np.arange(count)).reshape(shape)

    def _observe(self) -> Any:
        raise NotImplementedError


class DictObs(_Toy):
    observation_space = gym.spaces.Dict(
        {
            key: gym.spaces.Box(-np.inf, np.inf, shape=shape, dtype=np.float64)
            for key, shape in SHAPES.items()
        }
    )

    def _observe(self) -> dict[str, np.ndarray]:
        offsets = {"height": 100.0, "position": 200.0, "velocity": 300.0}
        return {key: self._values(SHAPES[key], offsets[key]) for key in set(SHAPES)}


class NestedObs(_Toy):
    """A Dict holding a Tuple: flattened arm[0] (2), arm[1] (1), then base (3)."""

    observation_space = gym.spaces.Dict(
        {
            "base": gym.spaces.Box(-9.0, 9.0, shape=(3,), dtype=np.float64),
            "arm": gym.spaces.Tuple(
                (
                    gym.spaces.Box(-20.0, 20.0, shape=(2,), dtype=np.float64),
                    gym.spaces.Box(0.0, 50.0, shape=(1,), dtype=np.float64),
                )
            ),
        }
    )

    def _observe(self) -> dict[str, Any]:
        return {
            "base": self._values((3,), 0.0),
            "arm": (self._values((2,), 10.0), self._values((1,), 20.0)),
        }


class ImageObs(_Toy):
    observation_space = gym.spaces.Box(0, 255, shape=(32, 32, 3), dtype=np.uint8)

    def _observe(self) -> np.ndarray:
        return np.zeros((32, 32, 3), dtype=np.uint8)


class PixelsAndStateObs(_Toy):
    observation_space = gym.spaces.Dict(
        {
            "pixels": gym.spaces.Box(0, 255, shape=(32, 32, 3), dtype=np.uint8),
            "state": gym.spaces.Box(-9.0, 9.0, shape=(4,), dtype=np.float64),
        }
    )

    def _observe(self) -> dict[str, np.ndarray]:
        return {"pixels": np.zeros((32, 32, 3), np.uint8), "state": self._values((4,), 0.0)}


class DiscreteObs(_Toy):
    observation_space = gym.spaces.Discrete(5)

    def _observe(self) -> int:
        return self._t % 5


class TextObs(_Toy):
    observation_space = gym.spaces.Text(8)

    def _observe(self) -> str:
        return "abc"


HORIZON = 60
for _name, _cls in {
    "DictObs": DictObs,
    "NestedObs": NestedObs,
    "ImageObs": ImageObs,
    "PixelsAndStateObs": PixelsAndStateObs,
    "DiscreteObs": DiscreteObs,
    "TextObs": TextObs,
}.items():
    if f"{_name}-v0" not in gym.registry:
        gym.register(
            f"{_name}-v0", entry_point=f"{__name__}:{_cls.__name__}", max_episode_steps=HORIZON
        )


def env_name(gym_id: str) -> str:
    """The ``module:id`` name under which groupwise makes a toy env in any process."""
    return f"{MODULE}:{gym_id}"
