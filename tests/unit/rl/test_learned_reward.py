import numpy as np
from stable_baselines3.common.vec_env import DummyVecEnv

from groupwise.envs import make_env
from groupwise.envs.spaces import encode_actions
from groupwise.rl.learned_reward import LearnedRewardVecEnv


def test_rewards_come_from_the_reward_fn_on_the_obs_the_action_saw():
    seen = []

    def reward_fn(obs, acts):
        seen.append((obs.copy(), acts.copy()))
        return obs[:, 0] * 100 + acts.argmax(axis=1)

    base = DummyVecEnv([lambda: make_env("GridWorld")] * 2)
    venv = LearnedRewardVecEnv(base, reward_fn)
    venv.seed(3)
    obs = venv.reset()
    actions = np.array([1, 4])
    next_obs, rewards, _dones, infos = venv.step(actions)
    np.testing.assert_allclose(rewards, obs[:, 0] * 100 + actions)
    np.testing.assert_array_equal(seen[0][0], obs)
    np.testing.assert_array_equal(seen[0][1], encode_actions(base.action_space, actions))
    # the true reward still flows, in the info
    assert all("true_reward" in info and 0 < info["true_reward"] <= 1 for info in infos)
    # the next step scores the new observation
    venv.step(np.array([0, 0]))
    np.testing.assert_array_equal(seen[1][0], next_obs)
