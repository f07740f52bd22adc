"""Whether an env's episodes last long enough to hold one behaviour of L steps.

A Gymnasium env may end an episode early (InvertedPendulum-v5 when the pole tips, 3–20
steps under random actions; Hopper-v5 when the hopper falls, 9–73). A pool needs windows of
L steps that do not cross an episode's end, so an env whose episodes never last L steps
cannot be taught at that L. `rl.rollout.sample_episodes_for_windows` finds out while it
samples a pool; `check_episode_length` finds out before anything is created (the app's
New-session page and ``groupwise serve --env``), with a random policy, in the same words.
"""

from typing import Any

import gymnasium as gym
import numpy as np

from groupwise.envs.registry import env_entry, make_env

GIVE_UP_EPISODES = 16
"""Episodes sampled without a single window among them before concluding that the env's
episodes are too short for the window length (a random Hopper-v5 falls after 9-73 steps; 16
such episodes show their spread)."""


def too_short_message(env_name: str, lengths: np.ndarray, length: int, window: str = "") -> str:
    """Why episodes of `lengths` (steps each, none reaching `length`) hold no behaviour;
    `window` says more about the window (e.g. " (clip_seconds = 1 s)")."""
    return (
        f"{len(lengths)} episodes of {env_name} lasted {lengths.min()}-{lengths.max()} steps "
        f"(median {np.median(lengths):g}), none long enough for one window of {length} "
        f"steps{window}: use a shorter fragment length, or an env or policy whose episodes "
        "last longer"
    )


def check_episode_length(
    name: str, length: int, rng: np.random.Generator, window: str = ""
) -> None:
    """Check that a random policy's episodes of env `name` can hold an `length`-step window.

    Plays up to `GIVE_UP_EPISODES` episodes of uniformly random actions (seeded from
    `rng`), each until the env ends it or it reaches `length` steps, and stops at the first
    that reaches it. The groupwise envs (`ENVS`) never end early and are not played. A
    trained policy may keep episodes alive longer or end them sooner: this is the check a
    round 0 pool, sampled from a fresh policy, passes.

    Raises:
        ValueError: unknown env, `length` < 1, or no episode lasted `length` steps (the
            message of `too_short_message`, with `window`, after "a random policy's").
    """
    if length < 1:
        raise ValueError(f"length must be >= 1, got {length}")
    if env_entry(name) is not None:
        return
    env = make_env(name)
    lengths: list[int] = []
    try:
        while len(lengths) < GIVE_UP_EPISODES:
            lengths.append(_episode_steps(env, length, rng))
            if lengths[-1] >= length:
                return
    finally:
        env.close()
    raise ValueError(
        "a random policy's " + too_short_message(name, np.array(lengths), length, window)
    )


def _episode_steps(env: gym.Env[Any, Any], length: int, rng: np.random.Generator) -> int:
    """Steps of one random episode, played until it ends or reaches `length` steps."""
    env.reset(seed=int(rng.integers(2**31 - 1)))
    env.action_space.seed(int(rng.integers(2**31 - 1)))
    for step in range(1, length + 1):
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        if terminated or truncated:
            return step
    return length
