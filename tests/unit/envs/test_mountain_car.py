"""Dense MountainCar: the reward formula on hand-made states, and the goal does not end it."""

import math

import numpy as np
import pytest

from groupwise.envs import TRUE_REWARD_KEY, make_env
from groupwise.envs.mountain_car import DenseMountainCarEnv, dense_reward


@pytest.mark.parametrize(
    ("position", "velocity", "action", "expected"),
    [
        # 20·|v| − 0.1 + |x + 0.5| − 0.1 + 100·[x ≥ 0.45 and v ≥ 0] − 0.1·a²
        (-0.5, 0.0, 0.0, 0.0 - 0.1 + 0.0 - 0.1 + 0.0 - 0.0),  # −0.2 at rest in the valley
        (0.5, 0.01, 1.0, 0.2 - 0.1 + 1.0 - 0.1 + 100.0 - 0.1),  # 100.9 past the goal
        (0.45, 0.0, 0.0, 0.0 - 0.1 + 0.95 - 0.1 + 100.0),  # 100.75 exactly at the goal
        (0.45, -0.01, 0.5, 0.2 - 0.1 + 0.95 - 0.1 + 0.0 - 0.025),  # 0.925 rolling back
        (-1.0, -0.05, -2.0, 1.0 - 0.1 + 0.5 - 0.1 + 0.0 - 0.4),  # 0.9, unclipped action
    ],
)
def test_dense_reward_formula(
    position: float, velocity: float, action: float, expected: float
) -> None:
    assert dense_reward(position, velocity, action) == pytest.approx(expected)


def _env_at(position: float, velocity: float) -> DenseMountainCarEnv:
    env = DenseMountainCarEnv()
    env.reset(seed=0)
    env.state = np.array([position, velocity])
    return env


def test_step_from_the_valley_floor() -> None:
    env = _env_at(-0.5, 0.0)
    obs, reward, terminated, truncated, info = env.step(np.array([0.0], dtype=np.float32))
    v = -0.0025 * math.cos(-1.5)  # gravity only: −0.000176843
    x = -0.5 + v
    np.testing.assert_allclose(obs, [x, v], atol=1e-7)
    assert reward == pytest.approx(20 * abs(v) - 0.1 + abs(x + 0.5) - 0.1, abs=1e-6)
    assert reward == pytest.approx(-0.1962863, abs=1e-6)
    assert info[TRUE_REWARD_KEY] == reward
    assert (terminated, truncated) == (False, False)


def test_reaching_the_goal_pays_the_bonus_and_does_not_terminate() -> None:
    env = _env_at(0.44, 0.07)
    obs, reward, terminated, _, _ = env.step(np.array([1.0], dtype=np.float32))
    # v = 0.07 + 0.0015 − 0.0025·cos(1.32) > 0.07 is clipped to 0.07, so x = 0.51.
    np.testing.assert_allclose(obs, [0.51, 0.07], atol=1e-6)
    assert reward == pytest.approx(1.4 - 0.1 + 1.01 - 0.1 + 100.0 - 0.1, abs=1e-5)  # 102.11
    assert terminated is False


def test_episode_at_the_goal_runs_to_250_steps() -> None:
    env = make_env("MountainCarContinuous")
    env.reset(seed=0)
    env.unwrapped.state = np.array([0.5, 0.05])
    bonuses = 0
    for t in range(1, 251):
        _, reward, terminated, truncated, _ = env.step(np.array([1.0], dtype=np.float32))
        bonuses += float(reward) > 50.0
        assert terminated is False
        assert truncated is (t == 250)
    assert bonuses == 250
