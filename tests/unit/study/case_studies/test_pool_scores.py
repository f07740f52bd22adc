"""The exploration measurement's pieces: a pool's scores and the strategy that records pools."""

import numpy as np

from groupwise.behaviour.pool import BehaviourPool
from groupwise.episodes.fragments import Fragment
from groupwise.study.case_studies.pool_scores import PoolRecorder, pool_scores


def _fragment(rewards: list[float], start: int) -> Fragment:
    steps = len(rewards)
    return Fragment(
        obs=np.zeros((steps, 2)),
        acts=np.zeros((steps, 1)),
        true_rewards=np.array(rewards),
        episode=0,
        start=start,
        reset_seed=0,
    )


def _pool() -> BehaviourPool:
    fragments = (_fragment([0.0, 0.0, 0.0], 0), _fragment([1.0, 2.0, 3.0], 3))
    return BehaviourPool(0, fragments, np.zeros((2, 0)))


def test_a_behaviours_score_is_its_mean_step_score():
    np.testing.assert_allclose(pool_scores(_pool()), [0.0, 2.0])


class _Asks:
    candidates = "the inner strategy's"

    def propose(self, pool, n_queries, rng):
        return [("query", n_queries)]


def test_the_recorder_scores_each_rounds_pool_and_lets_the_strategy_answer():
    recorder = PoolRecorder(_Asks())
    pool = _pool()
    assert recorder.propose(pool, 3, np.random.default_rng(0)) == [("query", 3)]
    assert list(recorder.scores) == [0]
    np.testing.assert_allclose(recorder.scores[0], [0.0, 2.0])
    assert recorder.candidates == "the inner strategy's"  # begin_round reads it
