"""Turning env actions into the float vectors the reward model and distances see."""

import gymnasium as gym
import numpy as np

from groupwise.types import FloatArray


def action_dim(space: gym.Space) -> int:
    """Width of the encoded action: n for Discrete(n) (one-hot), the flat size otherwise."""
    if isinstance(space, gym.spaces.Discrete):
        return int(space.n)
    if isinstance(space, gym.spaces.Box):
        return int(np.prod(space.shape))
    raise TypeError(f"unsupported action space {space!r}: use Discrete or Box")


def encode_actions(space: gym.Space, actions: np.ndarray) -> FloatArray:
    """Encode a batch of actions as float32 rows of width `action_dim(space)`.

    `actions` is (B,) ints for Discrete spaces (one-hot encoded here) or (B, *shape) for Box.
    """
    actions = np.asarray(actions)
    if isinstance(space, gym.spaces.Discrete):
        index = actions.reshape(-1).astype(np.int64) - int(space.start)
        encoded = np.zeros((index.shape[0], int(space.n)), dtype=np.float32)
        encoded[np.arange(index.shape[0]), index] = 1.0
        return encoded
    return actions.reshape(actions.shape[0], -1).astype(np.float32)


def observation_dim(space: gym.Space) -> int:
    """Width of the flattened observation."""
    if not isinstance(space, gym.spaces.Box):
        raise TypeError(f"unsupported observation space {space!r}: use Box")
    return int(np.prod(space.shape))
