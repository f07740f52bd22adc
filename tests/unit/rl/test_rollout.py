import numpy as np

from groupwise.envs import make_env
from groupwise.rl.policy import RandomPolicy
from groupwise.rl.rollout import evaluate, sample_trajectories


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
