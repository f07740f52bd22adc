"""Sampling whole episodes from a policy, with random exploration mixed in (SPEC §3.1).

All our envs have a fixed horizon, so a batch of episodes is stepped in lockstep and the
policy sees one batched observation per step. Sampling uses its own env instances, never
the ones PPO trains on.
"""

from collections.abc import Callable

import gymnasium as gym
import numpy as np

from groupwise.fragments import Trajectory
from groupwise.envs.spaces import encode_actions
from groupwise.rl.policy import Policy, random_actions

EnvFactory = Callable[[], gym.Env]

EXPLORATION_SEGMENT = 10
"""Mean length in steps of one random-action stretch (the agent and the random policy take
turns in stretches, like imitation's ExplorationWrapper, so random behaviour is visible in a
clip rather than single jittered steps)."""


def exploration_mask(
    n_episodes: int, horizon: int, fraction: float, rng: np.random.Generator
) -> np.ndarray:
    """(n_episodes, horizon) bool mask of steps that take a random action.

    A two-state Markov switch whose stationary share of random steps is `fraction`, with
    random stretches of mean length `EXPLORATION_SEGMENT`.
    """
    if not 0.0 <= fraction < 1.0:
        raise ValueError(f"exploration fraction must be in [0, 1), got {fraction}")
    mask = np.zeros((n_episodes, horizon), dtype=bool)
    if fraction == 0.0:
        return mask
    leave_random = 1.0 / EXPLORATION_SEGMENT
    enter_random = fraction / (1.0 - fraction) * leave_random
    state = rng.random(n_episodes) < fraction
    draws = rng.random((n_episodes, horizon))
    for t in range(horizon):
        mask[:, t] = state
        switch = np.where(state, draws[:, t] < leave_random, draws[:, t] < enter_random)
        state = state ^ switch
    return mask


def sample_trajectories(
    make_env: EnvFactory,
    policy: Policy,
    n_episodes: int,
    rng: np.random.Generator,
    exploration_fraction: float = 0.0,
    max_steps: int | None = None,
) -> list[Trajectory]:
    """Run `n_episodes` whole episodes of `policy` and return them.

    Episodes end at the env's truncation (its fixed horizon) or after `max_steps`. Each
    episode is reset with a seed drawn from `rng`, stored in the trajectory for replay.
    """
    envs = [make_env() for _ in range(n_episodes)]
    try:
        return _run_lockstep(envs, policy, rng, exploration_fraction, max_steps)
    finally:
        for env in envs:
            env.close()


def _run_lockstep(
    envs: list[gym.Env],
    policy: Policy,
    rng: np.random.Generator,
    exploration_fraction: float,
    max_steps: int | None,
) -> list[Trajectory]:
    space = envs[0].action_space
    seeds = rng.integers(0, 2**31 - 1, size=len(envs))
    current = np.stack([env.reset(seed=int(s))[0] for env, s in zip(envs, seeds, strict=True)])
    horizon = max_steps or _horizon(envs[0])
    explore = exploration_mask(len(envs), horizon, exploration_fraction, rng)
    obs, actions, rewards = [], [], []
    for t in range(horizon):
        action = np.asarray(policy.act(current.astype(np.float32), rng))
        if explore[:, t].any():
            action = action.copy()
            action[explore[:, t]] = random_actions(space, int(explore[:, t].sum()), rng)
        results = [env.step(a) for env, a in zip(envs, action, strict=True)]
        obs.append(current)
        actions.append(action)
        rewards.append([info.get("true_reward", r) for _, r, _, _, info in results])
        current = np.stack([r[0] for r in results])
        if any(term or trunc for _, _, term, trunc, _ in results):
            break
    obs_arr = np.stack(obs, axis=1)
    act_arr = np.stack(actions, axis=1)
    rew_arr = np.asarray(rewards, dtype=np.float64).T
    return [
        Trajectory(
            obs=obs_arr[i].reshape(obs_arr.shape[1], -1).astype(np.float32),
            acts=encode_actions(space, act_arr[i]),
            actions=act_arr[i],
            true_rewards=rew_arr[i],
            reset_seed=int(seeds[i]),
            episode=i,
        )
        for i in range(len(envs))
    ]


def _horizon(env: gym.Env) -> int:
    if env.spec is None or env.spec.max_episode_steps is None:
        raise ValueError(f"{env} has no fixed horizon: pass max_steps")
    return int(env.spec.max_episode_steps)


def evaluate(
    make_env: EnvFactory, policy: Policy, n_episodes: int, rng: np.random.Generator
) -> np.ndarray:
    """True (env) return of each of `n_episodes` episodes of `policy`, shape (n_episodes,)."""
    trajectories = sample_trajectories(make_env, policy, n_episodes, rng)
    return np.array([t.true_rewards.sum() for t in trajectories])
