"""The registry: spaces, horizons, no early termination, true reward, seeding, names."""

import sys
from collections.abc import Iterator
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

from groupwise.envs import (
    ENVS,
    TRUE_REWARD_KEY,
    horizon,
    make_env,
    make_standard_env,
    register_envs,
    resolve_id,
)
from groupwise.rl.policy import RandomPolicy
from groupwise.rl.rollout import sample_episodes_for_windows, sample_trajectories

SPACES = {
    "Hopper": (11, (3,)),
    "HalfCheetah": (17, (6,)),
    "Walker2d": (17, (6,)),
    "Reacher": (10, (2,)),
    "MountainCarContinuous": (2, (1,)),
    "GridWorld": (4, 5),
}
HORIZONS = {
    "Hopper": 1000,
    "HalfCheetah": 1000,
    "Walker2d": 1000,
    "Reacher": 1000,
    "MountainCarContinuous": 250,
    "GridWorld": 1000,
}


def test_registry_holds_exactly_the_six_envs() -> None:
    assert set(ENVS) == set(SPACES)
    for name, entry in ENVS.items():
        assert entry.gym_id == f"groupwise/{name}-v0"
        assert entry.gym_id in gym.registry


def test_registering_twice_changes_nothing() -> None:
    before = dict(gym.registry)
    register_envs()
    register_envs()
    assert dict(gym.registry) == before


@pytest.mark.parametrize("name", list(SPACES))
def test_observation_and_action_spaces(name: str) -> None:
    obs_dim, act = SPACES[name]
    env = make_env(name)
    obs, _ = env.reset(seed=0)
    assert env.observation_space.shape == (obs_dim,)
    assert obs.shape == (obs_dim,)
    if isinstance(act, int):
        assert env.action_space == gym.spaces.Discrete(act)
    else:
        assert isinstance(env.action_space, gym.spaces.Box)
        assert env.action_space.shape == act


@pytest.mark.parametrize("name", list(HORIZONS))
def test_episode_runs_exactly_to_the_horizon_without_termination(name: str) -> None:
    env = make_env(name)
    env.reset(seed=1)
    env.action_space.seed(1)
    assert horizon(name) == HORIZONS[name]
    for t in range(1, HORIZONS[name] + 1):
        _, reward, terminated, truncated, info = env.step(env.action_space.sample())
        assert terminated is False
        assert truncated is (t == HORIZONS[name])
        assert info[TRUE_REWARD_KEY] == pytest.approx(float(reward))


def test_fallen_hopper_keeps_going_until_the_horizon() -> None:
    env = make_env("Hopper")
    env.reset(seed=0)
    fell_at = None
    steps = 0
    truncated = False
    while not truncated:
        _, _, terminated, truncated, _ = env.step(np.array([-1.0, -1.0, -1.0], dtype=np.float32))
        steps += 1
        assert not terminated
        if fell_at is None and not env.unwrapped.is_healthy:
            fell_at = steps
    assert fell_at is not None and fell_at < 100
    assert steps == 1000


@pytest.mark.parametrize("name", ["Hopper", "Walker2d", "HalfCheetah", "Reacher"])
def test_mujoco_reward_is_the_standard_reward(name: str) -> None:
    ours, standard = make_env(name), make_standard_env(name)
    ours_obs, _ = ours.reset(seed=3)
    standard_obs, _ = standard.reset(seed=3)
    np.testing.assert_array_equal(ours_obs, standard_obs)
    rng = np.random.default_rng(0)
    for _ in range(40):
        action = rng.uniform(-1.0, 1.0, size=ours.action_space.shape).astype(np.float32)
        obs, reward, _, _, info = ours.step(action)
        expected_obs, expected, standard_done, _, _ = standard.step(action)
        np.testing.assert_array_equal(obs, expected_obs)
        assert reward == expected
        assert info[TRUE_REWARD_KEY] == reward
        if standard_done:
            break


@pytest.mark.parametrize("name", list(SPACES))
def test_same_seed_and_actions_give_same_observations(name: str) -> None:
    def rollout(seed: int) -> np.ndarray:
        env = make_env(name)
        first, _ = env.reset(seed=seed)
        env.action_space.seed(7)
        observations = [first] + [env.step(env.action_space.sample())[0] for _ in range(30)]
        return np.stack(observations)

    np.testing.assert_array_equal(rollout(5), rollout(5))
    starts = {tuple(rollout(seed)[0]) for seed in range(4)}
    assert len(starts) > 1


def test_standard_envs_are_gymnasiums_own() -> None:
    hopper = make_standard_env("Hopper")
    assert hopper.spec is not None and hopper.spec.id == "Hopper-v5"
    hopper.reset(seed=0)
    terminated = False
    for _ in range(100):
        terminated = hopper.step(np.array([-1.0, -1.0, -1.0], dtype=np.float32))[2]
        if terminated:
            break
    assert terminated
    reacher = make_standard_env("Reacher")
    assert reacher.spec is not None and reacher.spec.max_episode_steps == 50
    car = make_standard_env("MountainCarContinuous")
    assert car.spec is not None and car.spec.id == "MountainCarContinuous-v0"
    grid = make_standard_env("GridWorld")
    assert grid.spec is not None and grid.spec.id == "groupwise/GridWorld-v0"


def test_any_gymnasium_id_is_accepted() -> None:
    assert resolve_id("Hopper") == "groupwise/Hopper-v0"
    assert resolve_id("groupwise/Hopper-v0") == "groupwise/Hopper-v0"
    assert resolve_id("CartPole-v1") == "CartPole-v1"
    assert horizon("CartPole-v1") == 500
    env = make_env("Pendulum-v1")
    assert env.spec is not None and env.spec.id == "Pendulum-v1"


def test_unknown_name_raises_a_one_line_value_error_listing_known_names() -> None:
    with pytest.raises(ValueError, match="unknown env 'Hoper'") as caught:
        make_env("Hoper")
    message = str(caught.value)
    assert "\n" not in message
    for name in ENVS:
        assert name in message
    with pytest.raises(ValueError):
        horizon("NoSuchEnv-v0")
    with pytest.raises(ValueError):
        make_standard_env("NoSuchEnv-v0")


TOY_MODULE = "groupwise_toy_envs"
TOY_SOURCE = '''
"""Importing this module registers two toy envs, as a user's own env package would."""

import gymnasium as gym
import numpy as np


class Still(gym.Env):
    observation_space = gym.spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)
    action_space = gym.spaces.Discrete(2)

    def __init__(self, render_mode=None):
        self.render_mode = render_mode

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return np.zeros(1, dtype=np.float32), {}

    def step(self, action):
        return np.zeros(1, dtype=np.float32), float(action), False, False, {}


gym.register("Still-v0", entry_point=__name__ + ":Still", max_episode_steps=7)
gym.register("Endless-v0", entry_point=__name__ + ":Still")  # no time limit
'''


@pytest.fixture
def toy_module(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[str]:
    """A module on sys.path that registers "Still-v0" and "Endless-v0" when imported."""
    (tmp_path / f"{TOY_MODULE}.py").write_text(TOY_SOURCE)
    monkeypatch.syspath_prepend(str(tmp_path))
    yield TOY_MODULE
    sys.modules.pop(TOY_MODULE, None)
    for gym_id in ("Still-v0", "Endless-v0"):
        gym.registry.pop(gym_id, None)


def test_module_colon_id_imports_the_module_that_registers_the_env(toy_module: str) -> None:
    assert "Still-v0" not in gym.registry
    assert resolve_id(f"{toy_module}:Still-v0") == "Still-v0"
    env = make_env(f"{toy_module}:Still-v0")
    assert env.spec is not None and env.spec.id == "Still-v0"
    assert horizon(f"{toy_module}:Still-v0") == 7
    assert make_standard_env(f"{toy_module}:Still-v0").spec.id == "Still-v0"
    with pytest.raises(ValueError, match="registered no env 'Gone-v0'"):
        make_env(f"{toy_module}:Gone-v0")
    with pytest.raises(ValueError, match="cannot import module 'no_such_module_here'"):
        make_env("no_such_module_here:Still-v0")


def test_env_without_a_time_limit_needs_max_steps(toy_module: str) -> None:
    name = f"{toy_module}:Endless-v0"
    assert horizon(name) is None
    policy = RandomPolicy(make_env(name).action_space)
    with pytest.raises(ValueError, match=r"Endless-v0 has no fixed horizon.*pass max_steps"):
        sample_trajectories(lambda: make_env(name), policy, 2, np.random.default_rng(0))
    episodes = sample_trajectories(
        lambda: make_env(name), policy, 2, np.random.default_rng(0), max_steps=12
    )
    assert [len(t) for t in episodes] == [12, 12]
    with pytest.raises(ValueError, match="no fixed horizon"):
        sample_episodes_for_windows(lambda: make_env(name), policy, 4, 3, np.random.default_rng(0))
    episodes = sample_episodes_for_windows(
        lambda: make_env(name), policy, 8, 3, np.random.default_rng(0), max_steps=12
    )
    assert [len(t) for t in episodes] == [12, 12]  # 4 windows each
