"""GridWorld: moves, the distance reward on hand-placed cells, seeded starts, its renderer."""

import numpy as np
import pytest

from groupwise.envs import TRUE_REWARD_KEY, make_env
from groupwise.envs.gridworld import (
    AGENT_COLOUR,
    TARGET_COLOUR,
    GridWorldEnv,
    distance_reward,
)

STAY, RIGHT, LEFT, UP, DOWN = range(5)


def test_distance_reward_by_hand() -> None:
    assert distance_reward(np.array([2, 2]), np.array([2, 2])) == 1.0
    assert distance_reward(np.array([0, 0]), np.array([3, 4])) == pytest.approx(1 / 6)
    assert distance_reward(np.array([0, 0]), np.array([1, 1])) == pytest.approx(1 / (1 + 2**0.5))


def test_moves_walls_and_rewards_from_a_placed_start() -> None:
    env = GridWorldEnv()
    obs, _ = env.reset(seed=0, options={"agent": (0, 0), "target": (3, 4)})
    np.testing.assert_array_equal(obs, [0, 0, 3, 4])
    assert obs.dtype == np.float32
    obs, reward, *_ = env.step(LEFT)  # into the wall: stays at (0, 0), distance 5
    np.testing.assert_array_equal(obs, [0, 0, 3, 4])
    assert reward == pytest.approx(1 / 6)
    obs, reward, *_ = env.step(RIGHT)  # (1, 0): distance √20
    np.testing.assert_array_equal(obs[:2], [1, 0])
    assert reward == pytest.approx(1 / (1 + 20**0.5))  # 0.182744
    for _ in range(4):
        obs, reward, terminated, truncated, info = env.step(UP)  # up to (1, 4)
    np.testing.assert_array_equal(obs[:2], [1, 4])
    assert reward == pytest.approx(1 / 3)
    obs, reward, *_ = env.step(UP)  # into the top wall
    np.testing.assert_array_equal(obs[:2], [1, 4])
    env.step(RIGHT)
    obs, reward, terminated, truncated, info = env.step(RIGHT)  # on the target
    np.testing.assert_array_equal(obs, [3, 4, 3, 4])
    assert reward == 1.0 and info[TRUE_REWARD_KEY] == 1.0
    assert (terminated, truncated) == (False, False)
    obs, reward, *_ = env.step(STAY)
    assert reward == 1.0
    obs, _, *_ = env.step(DOWN)
    np.testing.assert_array_equal(obs[:2], [3, 3])


def test_random_starts_are_distinct_on_grid_and_seeded() -> None:
    env = GridWorldEnv()
    seen = set()
    for seed in range(200):
        obs, _ = env.reset(seed=seed)
        assert tuple(obs[:2]) != tuple(obs[2:])
        assert np.all((obs >= 0) & (obs <= 4))
        assert np.array_equal(obs, GridWorldEnv().reset(seed=seed)[0])
        seen.add(tuple(obs))
    assert len(seen) > 100


def test_invalid_action_and_placement_raise() -> None:
    env = GridWorldEnv()
    env.reset(seed=0)
    with pytest.raises(ValueError):
        env.step(5)
    with pytest.raises(ValueError):
        env.reset(options={"agent": (5, 0), "target": (0, 0)})


def test_frame_shows_agent_and_target_with_y_up() -> None:
    env = make_env("GridWorld", render_mode="rgb_array", width=100, height=80)
    env.reset(seed=0, options={"agent": (0, 4), "target": (4, 0)})
    frame = env.render()
    assert frame.shape == (80, 100, 3) and frame.dtype == np.uint8
    assert np.all(frame[8, 10] == AGENT_COLOUR)  # top-left cell centre: (0, 4)
    assert np.all(frame[72, 90] == TARGET_COLOUR)  # bottom-right cell centre: (4, 0)
    assert len(np.unique(frame.reshape(-1, 3), axis=0)) >= 4
