import gymnasium as gym
import numpy as np
import pytest

from groupwise.envs import TARGET_TOTAL_KEY, make_env
from groupwise.episodes.fragments import tile_fragments
from groupwise.rl.policy import RandomPolicy
from groupwise.rl.rollout import (
    evaluate,
    evaluate_episodes,
    sample_episodes_for_windows,
    sample_trajectories,
)


def make():
    return make_env("MountainCarContinuous")


def test_sampled_episodes_have_the_full_horizon_and_are_reproducible():
    policy = RandomPolicy(make().action_space)
    first = sample_trajectories(make, policy, 3, np.random.default_rng(4), 0.25)
    again = sample_trajectories(make, policy, 3, np.random.default_rng(4), 0.25)
    assert [len(t) for t in first] == [250, 250, 250]
    assert first[0].obs.shape == (250, 2) and first[0].acts.shape == (250, 1)
    for a, b in zip(first, again, strict=True):
        np.testing.assert_array_equal(a.obs, b.obs)
        np.testing.assert_array_equal(a.actions, b.actions)
    assert len({t.reset_seed for t in first}) == 3


def test_replaying_the_actions_from_the_reset_seed_reproduces_the_episode():
    (trajectory,) = sample_trajectories(
        make, RandomPolicy(make().action_space), 1, np.random.default_rng(0)
    )
    env = make()
    obs, _ = env.reset(seed=trajectory.reset_seed)
    replayed, rewards = [], []
    for action in trajectory.actions:
        replayed.append(obs)
        obs, reward, *_ = env.step(action)
        rewards.append(reward)
    np.testing.assert_allclose(np.array(replayed), trajectory.obs, rtol=1e-6)
    np.testing.assert_allclose(rewards, trajectory.true_rewards)


def test_discrete_actions_are_one_hot_encoded():
    env = make_env("GridWorld")
    (trajectory,) = sample_trajectories(
        lambda: make_env("GridWorld"),
        RandomPolicy(env.action_space),
        1,
        np.random.default_rng(0),
        max_steps=40,
    )
    assert trajectory.acts.shape == (40, 5)
    np.testing.assert_array_equal(trajectory.acts.argmax(axis=1), trajectory.actions)


def test_evaluate_returns_one_true_return_per_episode():
    returns = evaluate(make, RandomPolicy(make().action_space), 4, np.random.default_rng(1))
    assert returns.shape == (4,) and np.isfinite(returns).all()
    plain = evaluate_episodes(make, RandomPolicy(make().action_space), 4, np.random.default_rng(1))
    np.testing.assert_array_equal(plain.returns, returns)
    assert np.isnan(plain.scores).all()  # MountainCar has no episode score


def test_a_target_envs_episode_score_is_its_total_at_the_end_not_the_per_step_sum():
    def splits():
        return make_env("Walker2d-splits")

    policy = RandomPolicy(splits().action_space)
    evaluation = evaluate_episodes(splits, policy, 2, np.random.default_rng(2))
    episodes = sample_trajectories(splits, policy, 2, np.random.default_rng(2))
    env = splits()
    for i, episode in enumerate(episodes):  # replayed by hand
        env.reset(seed=episode.reset_seed)
        infos = [env.step(a)[4] for a in episode.actions]
        assert evaluation.scores[i] == episode.episode_score == infos[-1][TARGET_TOTAL_KEY]
        assert evaluation.returns[i] == pytest.approx(episode.true_rewards.sum())
    assert not np.allclose(evaluation.scores, evaluation.returns)


# An env that ends on its own: episode length drawn at reset (3-30 steps), time limit 20.
COUNTDOWN = "groupwise_test/Countdown-v0"
TIME_LIMIT = 20


class Countdown(gym.Env[np.ndarray, np.ndarray]):
    """Observation (step, episode length); reward 1 a step; terminates after `length` steps."""

    observation_space = gym.spaces.Box(0.0, 100.0, shape=(2,), dtype=np.float32)
    action_space = gym.spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.length, self.t = int(self.np_random.integers(3, 31)), 0
        return self._obs(), {}

    def step(self, action):
        self.t += 1
        return self._obs(), 1.0, self.t >= self.length, False, {}

    def _obs(self) -> np.ndarray:
        return np.array([self.t, self.length], dtype=np.float32)


@pytest.fixture(scope="module", autouse=True)
def _countdown_registered():
    gym.register(COUNTDOWN, entry_point=Countdown, max_episode_steps=TIME_LIMIT)
    yield
    del gym.registry[COUNTDOWN]


def countdown() -> gym.Env:
    return gym.make(COUNTDOWN)


def own_length(reset_seed: int) -> int:
    """How long the episode with this reset seed lasts: its drawn length or the time limit."""
    env = countdown()
    obs, _ = env.reset(seed=reset_seed)
    return min(int(obs[1]), TIME_LIMIT)


class CountingPolicy(RandomPolicy):
    """A random policy that remembers how many observations each call got."""

    def __init__(self, action_space: gym.Space) -> None:
        super().__init__(action_space)
        self.batch_sizes: list[int] = []

    def act(self, obs, rng):
        self.batch_sizes.append(obs.shape[0])
        return super().act(obs, rng)


def test_each_episode_of_a_batch_runs_to_its_own_end():
    policy = CountingPolicy(countdown().action_space)
    episodes = sample_trajectories(countdown, policy, 8, np.random.default_rng(0), 0.5)
    lengths = [len(t) for t in episodes]
    assert lengths == [own_length(t.reset_seed) for t in episodes]
    assert min(lengths) < max(lengths)  # some ended early; the others kept going
    assert TIME_LIMIT in lengths  # and some ran into the time limit
    for t in episodes:  # the steps of one episode, in order, none after its end
        np.testing.assert_array_equal(t.obs[:, 0], np.arange(len(t)))
        assert t.actions.shape == (len(t), 1) and t.true_rewards.sum() == len(t)
    assert [t.episode for t in episodes] == list(range(8))
    # finished envs are neither stepped nor shown to the policy
    assert policy.batch_sizes == [sum(n > step for n in lengths) for step in range(max(lengths))]
    again = sample_trajectories(countdown, policy, 8, np.random.default_rng(0), 0.5)
    for a, b in zip(episodes, again, strict=True):
        np.testing.assert_array_equal(a.actions, b.actions)


def test_max_steps_ends_episodes_before_their_own_end():
    policy = RandomPolicy(countdown().action_space)
    episodes = sample_trajectories(countdown, policy, 6, np.random.default_rng(1), max_steps=8)
    assert [len(t) for t in episodes] == [min(own_length(t.reset_seed), 8) for t in episodes]


def test_evaluate_sums_each_whole_episode():
    policy = RandomPolicy(countdown().action_space)
    rng = np.random.default_rng(2)
    seeds = np.random.default_rng(2).integers(0, 2**31 - 1, size=5)  # evaluate's reset seeds
    returns = evaluate(countdown, policy, 5, rng)
    np.testing.assert_array_equal(returns, [own_length(int(s)) for s in seeds])


def test_random_hopper_episodes_end_at_the_fall_and_every_one_gives_windows():
    def hopper() -> gym.Env:
        return gym.make("Hopper-v5")  # the standard env: terminates when it falls

    episodes = sample_trajectories(
        hopper, RandomPolicy(hopper().action_space), 8, np.random.default_rng(3)
    )
    lengths = [len(t) for t in episodes]
    assert max(lengths) < 1000 and len(set(lengths)) > 1
    fragments = tile_fragments(episodes, 5)
    assert {f.episode for f in fragments} == {t.episode for t in episodes}
    for f in fragments:  # no window reaches past the step at which its episode fell
        assert f.start + f.length <= lengths[f.episode]
    env = hopper()
    for t in episodes:  # replaying the actions: the episode terminates at its last step
        env.reset(seed=t.reset_seed)
        ended = [env.step(a)[2] for a in t.actions]
        assert ended == [False] * (len(t) - 1) + [True]


def test_sampling_for_windows_continues_until_there_are_enough():
    policy = RandomPolicy(countdown().action_space)
    episodes = sample_episodes_for_windows(
        countdown, policy, 25, 4, np.random.default_rng(4), batch=3
    )
    fragments = tile_fragments(episodes, 4)
    assert len(fragments) >= 25
    assert [t.episode for t in episodes] == list(range(len(episodes)))  # unique across batches
    assert len({f.key for f in fragments}) == len(fragments)
    # one batch fewer would not have been enough
    assert len(tile_fragments(episodes[: len(episodes) - 3], 4)) < 25


def test_sampling_for_windows_of_a_fixed_horizon_env_takes_one_batch():
    policy = RandomPolicy(make().action_space)
    episodes = sample_episodes_for_windows(make, policy, 12, 50, np.random.default_rng(0))
    assert [len(t) for t in episodes] == [250, 250, 250]  # ceil(12 / (250 // 50)) episodes


def test_sampling_for_windows_says_how_long_too_short_episodes_lasted():
    def long_limit() -> gym.Env:
        return gym.make(COUNTDOWN, max_episode_steps=100)  # but episodes end after <= 30 steps

    policy = RandomPolicy(countdown().action_space)
    with pytest.raises(ValueError, match=r"16 episodes of .*Countdown-v0 lasted \d+-\d+ steps"):
        sample_episodes_for_windows(long_limit, policy, 5, 40, np.random.default_rng(0))
    with pytest.raises(ValueError, match="at most 20 steps, fewer than one window of 21"):
        sample_episodes_for_windows(countdown, policy, 5, 21, np.random.default_rng(0))


def test_sampling_for_windows_stops_at_max_episodes():
    policy = RandomPolicy(countdown().action_space)
    episodes = sample_episodes_for_windows(
        countdown, policy, 1000, 4, np.random.default_rng(5), max_episodes=7
    )
    assert len(episodes) == 7
