"""What samples actions: the one-verb `Policy` interface and the uniform random policy."""

from typing import Protocol

import gymnasium as gym
import numpy as np

from groupwise.types import FloatArray


class Policy(Protocol):
    """Maps a batch of raw observations (B, *obs_shape) to a batch of env actions."""

    def act(self, obs: FloatArray, rng: np.random.Generator) -> np.ndarray: ...


def random_actions(space: gym.Space, n: int, rng: np.random.Generator) -> np.ndarray:
    """`n` uniformly random actions drawn from `rng` (not from the space's own RNG)."""
    if isinstance(space, gym.spaces.Discrete):
        return rng.integers(int(space.start), int(space.start) + int(space.n), size=n)
    if isinstance(space, gym.spaces.Box):
        low = np.broadcast_to(space.low, space.shape)
        high = np.broadcast_to(space.high, space.shape)
        return rng.uniform(low, high, size=(n, *space.shape)).astype(space.dtype)
    raise TypeError(f"unsupported action space {space!r}")


class RandomPolicy:
    """Uniform random actions: round 0's agent and the baseline of every learning test."""

    def __init__(self, action_space: gym.Space) -> None:
        self.action_space = action_space

    def act(self, obs: FloatArray, rng: np.random.Generator) -> np.ndarray:
        return random_actions(self.action_space, obs.shape[0], rng)
