"""What samples actions: the one-verb `Policy` interface and the uniform random policy."""

from typing import Protocol, runtime_checkable

import gymnasium as gym
import numpy as np

from groupwise.types import FloatArray, IntArray


class Policy(Protocol):
    """Maps a batch of raw observations (B, *obs_shape) to a batch of env actions."""

    def act(self, obs: FloatArray, rng: np.random.Generator) -> np.ndarray: ...


@runtime_checkable
class RowPolicy(Policy, Protocol):
    """A policy that acts by which episode of a sampling batch each row is (`rl.rollout`
    passes the episodes' numbers, (B,)): several policies stepped side by side in one batch,
    one call per step (`pool.recent.FreshVariants`)."""

    def act_rows(
        self, obs: FloatArray, episodes: IntArray, rng: np.random.Generator
    ) -> np.ndarray: ...


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


class BiasedPolicy:
    """A policy's actions pushed one way, the same way at every step: a Box action shifted by
    a fixed `offset` and clipped to the bounds; a Discrete action replaced, with probability
    `share`, by a fixed `action`. Exactly one of `offset` (Box) and `action` (Discrete) is given.

    A pool sampled partly from such variants of the current policy shows behaviours the
    policy itself rarely reaches (a walker that keeps one leg forward, a hopper that keeps
    leaning back): `biased_variants`, `LoopConfig.pool_variants`.
    """

    def __init__(
        self,
        base: Policy,
        space: gym.Space,
        *,
        offset: FloatArray | None = None,
        action: int | None = None,
        share: float = 0.5,
    ) -> None:
        if isinstance(space, gym.spaces.Box) and offset is None:
            raise ValueError("a Box action space needs an offset")
        if isinstance(space, gym.spaces.Discrete) and action is None:
            raise ValueError("a Discrete action space needs an action")
        self.base, self.space, self.offset, self.action, self.share = (
            base,
            space,
            offset,
            action,
            share,
        )

    def act(self, obs: FloatArray, rng: np.random.Generator) -> np.ndarray:
        return self.push(np.asarray(self.base.act(obs, rng)), rng)

    def push(self, actions: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """The base policy's `actions` (B, ...) pushed this variant's way."""
        if isinstance(self.space, gym.spaces.Discrete):
            assert self.action is not None
            return np.where(rng.random(actions.shape[0]) < self.share, self.action, actions)
        assert isinstance(self.space, gym.spaces.Box) and self.offset is not None
        shifted = np.clip(actions + self.offset, self.space.low, self.space.high)
        return shifted.astype(self.space.dtype)


def biased_variants(
    base: Policy, space: gym.Space, count: int, scale: float, rng: np.random.Generator
) -> list["BiasedPolicy"]:
    """`count` `BiasedPolicy` variants of `base`, each with its own bias drawn from `rng`:
    Box: an offset per dimension from U(−`scale`, `scale`) × half the action range;
    Discrete: a uniformly drawn action, taken instead of the policy's on a share `scale` of
    the steps.

    Raises:
        ValueError: `count` < 0 or `scale` outside [0, 1].
        TypeError: another action space.
    """
    if count < 0 or not 0.0 <= scale <= 1.0:
        raise ValueError(f"need count >= 0 and scale in [0, 1], got {count} and {scale}")
    if isinstance(space, gym.spaces.Box):
        half = (np.broadcast_to(space.high, space.shape) - space.low) / 2.0
        offsets = rng.uniform(-scale, scale, size=(count, *space.shape)) * half
        return [BiasedPolicy(base, space, offset=offset) for offset in offsets]
    if isinstance(space, gym.spaces.Discrete):
        start, n = int(space.start), int(space.n)
        chosen = rng.integers(start, start + n, size=count)
        return [BiasedPolicy(base, space, action=int(a), share=scale) for a in chosen]
    raise TypeError(f"unsupported action space {space!r}")
