"""PPE-style coverage: distance to the judged behaviours, and queries mixed by it."""

import numpy as np
import pytest

from groupwise.behaviour.pool import BehaviourPool
from groupwise.episodes.fragments import Fragment
from groupwise.preferences.dataset import PreferenceDataset
from groupwise.query.coverage import CoverageMix, coverage_scores, mixed_order, with_coverage
from groupwise.query.strategies import GroupSuggestions, PairwiseQueries

LENGTH = 4


def _still(levels, width: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """Behaviours that stand at (level, level, …) with zero actions: (obs, acts)."""
    obs = np.repeat(np.asarray(levels, np.float32)[:, None, None], LENGTH, axis=1)
    obs = np.repeat(obs, width, axis=2)
    return obs, np.zeros((len(levels), LENGTH, 1), np.float32)


def _judged(levels) -> PreferenceDataset:
    obs, acts = _still(levels)
    n = len(levels)
    pairs = np.arange(n - n % 2).reshape(-1, 2)
    return PreferenceDataset(obs, acts, np.zeros(n), pairs, np.ones(len(pairs), np.float32))


def test_a_behaviour_far_from_every_judged_one_scores_higher():
    judged = _still([0.0, 1.0, 2.0])
    scores = coverage_scores(*_still([1.0, 1.5, 6.0, -3.0]), *judged)
    assert scores[0] == pytest.approx(0.0)  # judged itself
    assert scores[0] < scores[1] < scores[3] < scores[2]  # 0.5, 3 and 4 levels away
    assert np.isnan(coverage_scores(*_still([1.0]), *_still([]))).all()  # nothing judged


def test_distances_are_in_standardised_features():
    # a dimension with a hundredfold spread does not drown the others
    obs = np.zeros((3, LENGTH, 2), np.float32)
    obs[1, :, 0] = 100.0  # judged: 0 and (100, 0)
    obs[2, :, 1] = 1.0  # far along the narrow dimension only
    acts = np.zeros((3, LENGTH, 1), np.float32)
    score = coverage_scores(obs[2:], acts[2:], obs[:2], acts[:2])
    assert score[0] > 1.0  # one step's sd in the narrow dimension is about 0.47


def test_mixed_order_by_hand():
    scores = np.array([5.0, 0.0, 9.0, 1.0, 8.0, 2.0, 7.0, 3.0])
    # 4 queries, half by coverage: the strategy's first 2, then the most uncovered of the
    # rest (index 2: 9.0), then the most covered of the rest (index 3: 1.0)
    assert mixed_order(scores, 4, 0.5) == [0, 1, 2, 3]
    assert mixed_order(scores, 4, 1.0) == [2, 4, 1, 3]
    assert mixed_order(scores, 4, 0.0) == [0, 1, 2, 3]
    assert mixed_order(scores[:3], 5, 1.0) == [2, 0, 1]  # fewer candidates than asked


def _pool(levels, rng) -> BehaviourPool:
    obs, acts = _still(levels)
    fragments = tuple(
        Fragment(o, a, np.zeros(LENGTH), i, 0, i)
        for i, (o, a) in enumerate(zip(obs, acts, strict=True))
    )
    return BehaviourPool(0, fragments, rng.normal(size=(len(levels), 3)))


def test_the_mix_asks_the_uncovered_and_the_covered_beside_the_strategys_own():
    rng = np.random.default_rng(0)
    pool = _pool(np.linspace(0.0, 10.0, 24), rng)
    judged = _judged([0.0, 0.0])  # only the pool's first behaviours are covered
    strategy = PairwiseQueries(candidates=5)
    mixed = CoverageMix(strategy, 1.0, judged).propose(pool, 6, np.random.default_rng(1))
    assert len(mixed) == 6
    distance = [np.mean([*q.left, *q.right]) for q in mixed]  # index ~ level ~ distance
    assert min(distance[:3]) > max(distance[3:])  # three uncovered first, three covered
    plain = strategy.propose(pool, 6, np.random.default_rng(1))
    assert with_coverage(strategy, 0.0, judged) is strategy
    none_judged = CoverageMix(strategy, 1.0, _judged([])).propose(pool, 6, np.random.default_rng(1))
    assert none_judged == plain  # nothing judged yet: the strategy's own queries


def test_the_mix_wraps_the_group_suggestions():
    rng = np.random.default_rng(2)
    pool = _pool(np.repeat(np.linspace(0.0, 10.0, 8), 3) + rng.normal(0, 0.01, 24), rng)
    groups = GroupSuggestions()
    mixed = CoverageMix(groups, 0.5, _judged([0.0, 0.5])).propose(pool, 4, rng)
    own = groups.propose(pool, 4, rng)
    assert len(mixed) == 4 and mixed[:2] == own[:2]  # half the list is the strategy's
    assert CoverageMix(groups, 0.5, _judged([0.0])).candidates(pool) == groups.candidates(pool)
    with pytest.raises(ValueError):
        CoverageMix(groups, 1.5, _judged([0.0]))
