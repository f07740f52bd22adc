import numpy as np

from groupwise.behaviour.pool import BehaviourPool
from groupwise.episodes.fragments import Fragment
from groupwise.query.strategies import PairwiseQueries
from groupwise.teachers import Feedback, PairwiseTeacher
from groupwise.teachers.noise import perceived_returns, preference


def _pool(returns: list[float], k: int = 3) -> BehaviourPool:
    fragments = tuple(
        Fragment(
            obs=np.zeros((30, 2), dtype=np.float32),
            acts=np.zeros((30, 1), dtype=np.float32),
            true_rewards=np.full(30, r / 30),
            episode=i,
            start=0,
            reset_seed=0,
        )
        for i, r in enumerate(returns)
    )
    rng = np.random.default_rng(0)
    return BehaviourPool(0, fragments, rng.normal(size=(len(returns), k)))


def test_noise_has_the_specified_scale():
    rng = np.random.default_rng(0)
    noisy = perceived_returns(np.zeros(200_000), length=30, sigma=0.25, rng=rng)
    assert abs(noisy.std() - 7.5) < 0.05


def test_noise_free_dm_is_always_right():
    pool = _pool([float(r) for r in range(20)])
    judgements = Feedback(PairwiseQueries(), PairwiseTeacher(sigma=0.0)).gather(
        pool, 50, np.random.default_rng(0)
    )
    assert len(judgements) == 50
    true = pool.true_returns
    for j in judgements:
        (a,), (b,) = j.left, j.right
        assert j.label == (1.0 if true[a] > true[b] else 0.0)


def test_noisy_dm_errs_more_on_close_pairs_and_is_seeded():
    pool = _pool([0.0, 1.0, 100.0])
    dm = Feedback(PairwiseQueries(candidates=1), PairwiseTeacher(sigma=0.25))
    first = dm.gather(pool, 300, np.random.default_rng(5))
    assert first == dm.gather(pool, 300, np.random.default_rng(5))
    true = pool.true_returns
    wrong_close = [
        j
        for j in first
        if {j.left[0], j.right[0]} == {0, 1}
        and j.label != (1.0 if true[j.left[0]] > true[j.right[0]] else 0.0)
    ]
    close = [j for j in first if {j.left[0], j.right[0]} == {0, 1}]
    far = [j for j in first if 2 in (j.left[0], j.right[0])]
    wrong_far = [j for j in far if (j.label == 1.0) != (j.left[0] == 2)]
    assert len(wrong_close) / len(close) > 0.3  # a 1-point gap under noise of sd 7.5
    assert len(wrong_far) / len(far) < 0.01


def test_boltzmann_preference_follows_the_logistic():
    rng = np.random.default_rng(0)
    picks = [preference(1.0, 0.0, rng, beta=1.0) for _ in range(20_000)]
    assert abs(np.mean(picks) - 1 / (1 + np.exp(-1))) < 0.01
