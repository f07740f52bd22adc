"""The issue-41 diagnostic: the learned reward's ranking of the policy's own steps."""

import math

import numpy as np
import pytest

from groupwise.config import PPOConfig
from groupwise.envs import make_env
from groupwise.rl.ppo import PPOAgent
from groupwise.study.case_studies.reward_rank import (
    rank_rng,
    reward_rank,
    spearman,
    splits_postures,
)

SMALL = PPOConfig(n_envs=2, n_steps=64, batch_size=32, n_epochs=1, tensorboard=False)


def pendulum():
    return make_env("Pendulum-v1")


def pendulum_reward(obs, acts):
    """Pendulum-v1's own reward of a step, from the observation before it and the action:
    −(θ² + 0.1 θ̇² + 0.001 u²), θ wrapped to [−π, π), u clipped to ±2 (Gymnasium's code)."""
    theta = np.arctan2(obs[:, 1], obs[:, 0])
    torque = np.clip(acts[:, 0], -2.0, 2.0)
    return -(theta**2 + 0.1 * obs[:, 2] ** 2 + 0.001 * torque**2)


def test_a_reward_equal_to_the_true_one_ranks_perfectly_and_its_negative_backwards():
    agent = PPOAgent(pendulum, SMALL, seed=0)
    same = reward_rank(pendulum, agent, pendulum_reward, 2, rank_rng(0, 0))
    flipped = reward_rank(pendulum, agent, lambda o, a: -pendulum_reward(o, a), 2, rank_rng(0, 0))
    assert same.steps == flipped.steps == 4 * 200  # 2 greedy + 2 stochastic episodes
    assert same.rho > 0.9999  # float32 observations: equal up to rounding
    assert flipped.rho < -0.9999
    assert same.by_posture == {}


def test_the_same_stream_gives_the_same_measurement():
    agent = PPOAgent(pendulum, SMALL, seed=0)
    reward = lambda o, a: o[:, 2]  # noqa: E731  (θ̇: some ranking, not the true one)
    first = reward_rank(pendulum, agent, reward, 1, rank_rng(3, 1))
    again = reward_rank(pendulum, agent, reward, 1, rank_rng(3, 1))
    assert first.rho == again.rho and -1.0 < first.rho < 1.0


def test_spearman_by_hand():
    assert spearman(np.array([1.0, 2.0, 3.0]), np.array([10.0, 20.0, 30.0])) == pytest.approx(1.0)
    assert spearman(np.array([1.0, 2.0, 3.0]), np.array([3.0, 1.0, 2.0])) == pytest.approx(-0.5)
    assert math.isnan(spearman(np.ones(4), np.arange(4.0)))
    with pytest.raises(ValueError):
        spearman(np.ones(3), np.ones(4))


def _walker_obs(qpos):
    return np.concatenate([qpos[1:], np.zeros(9)])  # Walker2d-v5: qpos without x, then qvel


def test_walker_postures_tell_a_held_split_and_the_wide_tilted_stance_apart():
    classes = splits_postures(lambda: make_env("Walker2d-splits"))
    standing = np.zeros(9)
    standing[1] = 1.25
    # found by lowering each pose onto the floor: both feet down in each
    split = np.array([0, 0.91004, -math.pi / 4, 0, 0, -0.8, -math.pi / 2, 0, 0.6])
    stance = np.array([0, 0.58164, -1.1, 0, 0, -0.8, -2.4, 0, -0.8])  # torso 63° back
    got = classes(np.stack([_walker_obs(q) for q in (standing, split, stance)]))
    assert got["split"].tolist() == [False, True, False]
    assert got["nonsplit"].tolist() == [True, False, True]
    assert got["stance"].tolist() == [False, False, True]
