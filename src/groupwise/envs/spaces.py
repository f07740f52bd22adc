"""Turning env actions into the float vectors the reward model and distances see, and which
observation spaces they can see at all.

The reward model, the behaviour distances and PPO's policy read one flat float vector per
step. A Box of numbers is that vector; a Dict or Tuple of such Boxes (the DeepMind Control
suite's observations, issue 42) becomes one through `groupwise.envs.flatten`. Anything else
is refused before a run or session is created, with the one line of `observation_refusal`.
"""

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
    """Width of the flattened observation of a Box space (`make_env` flattens Dict and Tuple
    spaces into one)."""
    if not isinstance(space, gym.spaces.Box):
        raise TypeError(f"unsupported observation space {space!r}: use Box")
    return int(np.prod(space.shape))


def is_image(space: gym.spaces.Box) -> bool:
    """Whether a Box holds images: three or more axes (height, width, channels), or uint8
    values on two or more (a grey image). A reward model over raw pixels is not what the
    behaviour distances or the reward nets here are built for."""
    return len(space.shape) >= 3 or (space.dtype == np.uint8 and len(space.shape) >= 2)


def observation_refusal(space: gym.Space, path: str = "") -> str | None:
    """Why an env with observation space `space` cannot be taught here, or None when it can.

    It can when the space is a Box of numbers that is not an image (`is_image`), or a Dict or
    Tuple (nested to any depth) whose every leaf is such a Box. `path` names the part being
    checked, e.g. "['pixels']", in the reason.
    """
    where = f" at {path}" if path else ""
    if isinstance(space, gym.spaces.Box):
        if is_image(space):
            return (
                f"its observation{where} is an image, Box{space.shape} of {space.dtype}: "
                "groupwise learns rewards from state vectors, not pixels; use the env's "
                "state observations"
            )
        if not np.issubdtype(space.dtype, np.number) or space.dtype == np.bool_:
            return f"its observation{where} is a Box of {space.dtype}, not of numbers"
        return None
    if isinstance(space, gym.spaces.Dict):
        if not space.spaces:
            return f"its observation{where} is an empty Dict"
        for key, part in space.spaces.items():
            if (reason := observation_refusal(part, f"{path}[{key!r}]")) is not None:
                return reason
        return None
    if isinstance(space, gym.spaces.Tuple):
        if not space.spaces:
            return f"its observation{where} is an empty Tuple"
        for index, part in enumerate(space.spaces):
            if (reason := observation_refusal(part, f"{path}[{index}]")) is not None:
                return reason
        return None
    return (
        f"its observation{where} is {type(space).__name__} ({space}): groupwise needs a Box "
        "of numbers, or a Dict or Tuple of them, to compare behaviours and learn a reward"
    )
