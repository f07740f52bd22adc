"""Behaviours with varied returns for studies: a mix of random, biased-random and trained policies.

Uniform random actions alone give behaviours whose true returns barely differ (a random Hopper
falls and lies still), which makes "do clusters keep returns alike?" an empty question. So a
study mixes policies:

- "random": uniform random actions;
- "biased-k": random actions with a fixed bias drawn once per policy. Box actions: uniform
  over the bounds plus an offset, drawn per dimension from U(−s, s) × half the range, then
  clipped to the bounds (so the action mean moves towards one side, e.g. a Hopper that keeps
  pushing one joint). Discrete actions: a categorical distribution with logits drawn from
  N(0, (4 s)²) (so some moves are much likelier, e.g. a GridWorld agent that drifts one way);
- checkpoints of partly trained PPO policies, when given, instead of the biased ones.

Trajectories are dealt round-robin over the policies (trajectory i comes from policy
i mod P), and each contributes `windows` windows of L steps, drawn uniformly without
replacement among its non-overlapping tiles.
"""

import dataclasses
from collections.abc import Callable, Sequence

import gymnasium as gym
import numpy as np

from groupwise.envs import make_env
from groupwise.episodes.fragments import Fragment, tile_fragments
from groupwise.rl.policy import Policy, RandomPolicy, random_actions
from groupwise.rl.rollout import sample_trajectories
from groupwise.types import FloatArray


class BiasedRandomPolicy:
    """Random actions with a fixed bias (module docstring). Exactly one of `offset` (Box)
    and `probabilities` (Discrete) is given."""

    def __init__(
        self,
        space: gym.Space,
        offset: FloatArray | None = None,
        probabilities: FloatArray | None = None,
    ) -> None:
        if isinstance(space, gym.spaces.Box) and offset is None:
            raise ValueError("a Box action space needs an offset")
        if isinstance(space, gym.spaces.Discrete) and probabilities is None:
            raise ValueError("a Discrete action space needs probabilities")
        self.space = space
        self.offset = offset
        self.probabilities = probabilities

    def act(self, obs: FloatArray, rng: np.random.Generator) -> np.ndarray:
        n = obs.shape[0]
        if isinstance(self.space, gym.spaces.Discrete):
            assert self.probabilities is not None
            choice = rng.choice(len(self.probabilities), size=n, p=self.probabilities)
            return np.asarray(choice) + int(self.space.start)
        assert isinstance(self.space, gym.spaces.Box) and self.offset is not None
        actions = random_actions(self.space, n, rng) + self.offset
        return np.clip(actions, self.space.low, self.space.high).astype(self.space.dtype)


def biased_policies(
    space: gym.Space, count: int, scale: float, rng: np.random.Generator
) -> list[tuple[str, Policy]]:
    """`count` biased random policies named "biased-0" … (module docstring)."""
    policies: list[tuple[str, Policy]] = []
    for k in range(count):
        if isinstance(space, gym.spaces.Discrete):
            logits = rng.normal(0.0, 4.0 * scale, size=int(space.n))
            p = np.exp(logits - logits.max())
            policy = BiasedRandomPolicy(space, probabilities=p / p.sum())
        elif isinstance(space, gym.spaces.Box):
            half = (np.broadcast_to(space.high, space.shape) - space.low) / 2.0
            offset = rng.uniform(-scale, scale, size=space.shape) * half
            policy = BiasedRandomPolicy(space, offset=offset)
        else:
            raise TypeError(f"unsupported action space {space!r}")
        policies.append((f"biased-{k}", policy))
    return policies


def mixed_policies(
    env: str,
    checkpoints: Sequence[str],
    biased: int,
    scale: float,
    rng: np.random.Generator,
    load: Callable[[str, str], Policy] | None = None,
) -> list[tuple[str, Policy]]:
    """ "random" plus either the checkpoint policies (when `checkpoints` is not empty, loaded
    with `load`, default `groupwise.rl.policy_files.load_policy`) or `biased` biased random ones."""
    probe = make_env(env)
    space = probe.action_space
    probe.close()
    policies: list[tuple[str, Policy]] = [("random", RandomPolicy(space))]
    if checkpoints:
        loader = load or _load_checkpoint
        policies += [(str(path), loader(str(path), env)) for path in checkpoints]
    else:
        policies += biased_policies(space, biased, scale, rng)
    return policies


def _load_checkpoint(path: str, env: str) -> Policy:
    from groupwise.rl.policy_files import load_policy

    return load_policy(path, env)


def sample_mixed(
    env: str,
    policies: Sequence[tuple[str, Policy]],
    trajectories: int,
    windows: int,
    length: int,
    rng: np.random.Generator,
) -> tuple[list[Fragment], list[str]]:
    """`trajectories` episodes dealt round-robin over `policies`, `windows` random windows of
    `length` steps from each. Returns the fragments (trajectories × windows, episodes
    numbered 0 … trajectories − 1) and the name of the policy behind each.

    Raises:
        ValueError: an episode has fewer than `windows` windows.
    """
    if trajectories < 1 or windows < 1:
        raise ValueError(f"need >= 1 trajectories and windows, got {trajectories}, {windows}")
    fragments: list[Fragment] = []
    sources: list[str] = []
    for k, (name, policy) in enumerate(policies):
        count = len(range(k, trajectories, len(policies)))
        if count == 0:
            continue
        episodes = sample_trajectories(lambda: make_env(env), policy, count, rng)
        for i, episode in enumerate(episodes):
            number = k + i * len(policies)  # its round-robin position
            tiles = tile_fragments([dataclasses.replace(episode, episode=number)], length)
            if len(tiles) < windows:
                raise ValueError(f"an episode of {len(episode)} steps has < {windows} windows")
            for t in np.sort(rng.choice(len(tiles), size=windows, replace=False)):
                fragments.append(tiles[t])
                sources.append(name)
    order = sorted(range(len(fragments)), key=lambda i: (fragments[i].episode, fragments[i].start))
    return [fragments[i] for i in order], [sources[i] for i in order]
