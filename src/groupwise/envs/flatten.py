"""One flat observation vector from a Dict or Tuple of Boxes, in a documented, stable order.

The DeepMind Control suite observes a dict (Walker-walk: ``orientations`` (14,), ``height``
(), ``velocity`` (9,)), and so may any Gymnasium env. The reward model, the behaviour
distances and PPO read one vector per step, so `make_env` wraps such an env in
`FlatObservation` (issue 42). The order is fixed by the space alone, never by the order in
which an env happens to build its dict:

- a Dict's entries in the sorted order of their keys (compared as strings), whatever order
  the env's dict or space lists them in (dm_control's own order is its task's
  ``get_observation``; Walker-walk's flat vector is height, orientations, velocity);
- a Tuple's entries by index;
- nested spaces depth first, the same way;
- each Box leaf's values in C order (its last axis fastest), a scalar Box as one value.

`flat_layout` lists the leaves with their slices of the vector, so a column of the flat
observation can be named (``docs/bring-your-own.md``).
"""

from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np

from groupwise.envs.spaces import observation_refusal
from groupwise.types import FloatArray


@dataclass(frozen=True)
class ObsLeaf:
    """One Box of a structured observation space and its place in the flat vector."""

    path: tuple[str | int, ...]
    """Keys (Dict) and indices (Tuple) from the top of the space down to this Box."""
    shape: tuple[int, ...]
    """The Box's shape; () for a scalar."""
    start: int
    """First column of the flat vector that holds this Box."""
    size: int
    """Columns it takes: the product of `shape` (1 for a scalar)."""

    @property
    def name(self) -> str:
        """The path as written in Python, e.g. ``['velocity']`` or ``[0]['joints']``."""
        return "".join(f"[{part!r}]" for part in self.path)


def flat_layout(space: gym.Space) -> tuple[ObsLeaf, ...]:
    """The Box leaves of a Box, Dict or Tuple space in flattening order (module docstring).

    Raises:
        ValueError: a space `observation_refusal` refuses (its one-line reason).
    """
    if (reason := observation_refusal(space)) is not None:
        raise ValueError(reason)
    leaves: list[ObsLeaf] = []
    _collect(space, (), leaves)
    return tuple(leaves)


def _collect(space: gym.Space, path: tuple[str | int, ...], leaves: list[ObsLeaf]) -> None:
    if isinstance(space, gym.spaces.Dict):
        for key in sorted(space.spaces, key=str):
            _collect(space.spaces[key], (*path, key), leaves)
    elif isinstance(space, gym.spaces.Tuple):
        for index, part in enumerate(space.spaces):
            _collect(part, (*path, index), leaves)
    else:
        start = leaves[-1].start + leaves[-1].size if leaves else 0
        shape = tuple(int(n) for n in space.shape or ())
        leaves.append(ObsLeaf(path, shape, start, int(np.prod(shape))))


def _pick(observation: Any, path: tuple[str | int, ...]) -> Any:
    for part in path:
        observation = observation[part]
    return observation


def flatten_observation(leaves: tuple[ObsLeaf, ...], observation: Any) -> FloatArray:
    """The (D,) float32 vector of a structured `observation`, D the leaves' total size."""
    parts = [np.asarray(_pick(observation, leaf.path), dtype=np.float32) for leaf in leaves]
    return np.concatenate([part.reshape(-1) for part in parts])


class FlatObservation(gym.ObservationWrapper[FloatArray, Any, Any]):
    """An env whose Dict or Tuple of Box observations arrive as one float32 Box vector, in the
    order of `flat_layout` (module docstring); `leaves` names its columns."""

    def __init__(self, env: gym.Env[Any, Any]) -> None:
        super().__init__(env)
        self.leaves = flat_layout(env.observation_space)
        lows, highs = [], []
        for leaf in self.leaves:
            box = _pick_space(env.observation_space, leaf.path)
            lows.append(np.broadcast_to(box.low, leaf.shape).reshape(-1))
            highs.append(np.broadcast_to(box.high, leaf.shape).reshape(-1))
        self.observation_space = gym.spaces.Box(
            np.concatenate(lows).astype(np.float32),
            np.concatenate(highs).astype(np.float32),
            dtype=np.float32,
        )

    def observation(self, observation: Any) -> FloatArray:
        return flatten_observation(self.leaves, observation)


def _pick_space(space: gym.Space, path: tuple[str | int, ...]) -> gym.spaces.Box:
    for part in path:
        space = space[part]  # type: ignore[index]  # Dict by key, Tuple by index
    assert isinstance(space, gym.spaces.Box)
    return space
