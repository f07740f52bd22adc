"""Scoring a policy on a target: episode scores are the env's own totals, rates by threshold."""

import numpy as np
import pytest

from groupwise.envs import TARGET_TOTAL_KEY, TARGETS, make_env
from groupwise.rl.policy import RandomPolicy
from groupwise.study.case_studies.target_evaluation import evaluate_target


def test_evaluation_scores_each_episode_by_the_envs_total() -> None:
    make = lambda: make_env("Walker2d-splits")  # noqa: E731
    policy = RandomPolicy(make().action_space)
    evaluation = evaluate_target(make, policy, 2, np.random.default_rng(0))
    assert evaluation.scores.shape == (2,) and len(evaluation.actions) == 2
    assert [len(a) for a in evaluation.actions] == [1000, 1000]
    env = make()
    for i, seed in enumerate(evaluation.reset_seeds):  # replaying gives the same scores
        env.reset(seed=seed)
        infos = [env.step(a)[4] for a in evaluation.actions[i]]
        assert infos[-1][TARGET_TOTAL_KEY] == evaluation.scores[i]
        assert sum(info["true_reward"] for info in infos) == pytest.approx(evaluation.returns[i])
    target = TARGETS["walker-splits"]
    assert evaluation.success_rate(target) == 0.0  # a random walker falls within a second
    with pytest.raises(ValueError):
        evaluate_target(make, policy, 0, np.random.default_rng(0))
