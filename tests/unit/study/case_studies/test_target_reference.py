import numpy as np
import pytest

from groupwise.config import PPOConfig
from groupwise.envs import TARGETS, make_env
from groupwise.envs.targets import TARGET_SCORE_KEY
from groupwise.study.case_studies.target_reference import ScoreAsReward, train_on_score


def test_the_reward_is_the_step_score():
    env = ScoreAsReward(make_env(TARGETS["walker-splits"].env))
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    rewards, scores = [], []
    for _ in range(20):
        _, reward, _, _, info = env.step(env.action_space.sample() * rng.uniform())
        rewards.append(reward)
        scores.append(info[TARGET_SCORE_KEY])
    env.close()
    assert rewards == scores and any(r != 0 for r in rewards)


def test_ppo_on_the_score_is_scored_every_so_many_steps():
    cfg = PPOConfig(n_envs=2, n_steps=64, batch_size=32, n_epochs=1, tensorboard=False)
    target = TARGETS["halfcheetah-standup"]
    points = train_on_score(target, cfg, steps=256, every=128, seed=0, eval_episodes=1)
    assert [p.steps for p in points] == [128, 256]
    assert all(p.target == target.name and p.success_rate in (0.0, 1.0) for p in points)
    with pytest.raises(ValueError):
        train_on_score(target, cfg, steps=256, every=0, seed=0)
