import numpy as np
import pytest

from groupwise.behaviour.pool import BehaviourPool
from groupwise.config import RunConfig
from groupwise.episodes.fragments import Fragment
from groupwise.preferences.dataset import wrong_labels
from groupwise.preferences.judgement import EQUAL, LEFT_BETTER, RIGHT_BETTER, Judgement
from groupwise.preferences.pairs import covering_pairs
from groupwise.query.strategies import PairwiseQueries
from groupwise.teachers import DECISION_MAKERS, Feedback
from groupwise.teachers.group_decision import Perception, SimulatedTeacher, decide
from groupwise.teachers.imperfect import (
    TEACHERS,
    EqualWhenClose,
    Imperfection,
    Mistake,
    SkipWhenBothBelow,
)


def _error_rate(pool, judgements):
    pairs = [p for j in judgements for p in covering_pairs(j, np.random.default_rng(0))]
    true = pool.true_returns
    a, b = np.array([p.a for p in pairs]), np.array([p.b for p in pairs])
    return float(wrong_labels(true[a], true[b], np.array([p.label for p in pairs])).mean())


def test_mistake_rate_on_pairs_is_epsilon(make_pool):
    pool = make_pool([0.0, 100.0])
    teacher = SimulatedTeacher(Perception(0.0), (decide, Mistake(0.1)))
    judgements = Feedback(PairwiseQueries(), teacher).gather(pool, 5000, np.random.default_rng(0))
    assert len(judgements) == 5000
    assert _error_rate(pool, judgements) == pytest.approx(0.1, abs=0.015)


def test_mistake_rate_on_groups_is_epsilon(make_pool):
    pool = make_pool([0.0, 1.0, 100.0, 101.0])
    teacher = SimulatedTeacher(Perception(0.0), (decide, Mistake(0.2)))
    rng = np.random.default_rng(1)
    judgements = [teacher.judge(pool, (0, 1), (2, 3), rng) for _ in range(4000)]
    flipped = np.mean([j is not None and j.label == LEFT_BETTER for j in judgements])
    assert flipped == pytest.approx(0.2, abs=0.02)
    assert all(j is not None and j.left == (0, 1) for j in judgements)


def test_skip_when_both_look_bad(make_pool):
    pool = make_pool([float(r) for r in range(100)])  # 10 % quantile 9.9
    teacher = SimulatedTeacher(Perception(0.0), (SkipWhenBothBelow(0.1), decide))
    rng = np.random.default_rng(0)
    assert teacher.judge(pool, (0,), (9,), rng) is None
    assert teacher.judge(pool, (0, 1), (5, 8), rng) is None
    assert teacher.judge(pool, (0,), (50,), rng) == Judgement((0,), (50,), RIGHT_BETTER)
    # a skipped query uses up its query
    dm = Feedback(
        PairwiseQueries(), SimulatedTeacher(Perception(0.0), (SkipWhenBothBelow(0.5), decide))
    )
    judgements = dm.gather(pool, 400, np.random.default_rng(0))
    assert 50 < len(judgements) < 400


def test_equal_when_close(make_pool):
    pool = make_pool([float(r) for r in range(100)])  # std 28.87: threshold 2.887
    teacher = SimulatedTeacher(Perception(0.0), (EqualWhenClose(0.1), decide))
    rng = np.random.default_rng(0)
    assert teacher.judge(pool, (10,), (12,), rng) == Judgement((10,), (12,), EQUAL)
    # equal keeps the groups whole: no outlier removal without a winner
    j = teacher.judge(pool, (10, 30), (20, 21), rng)
    assert j is not None and j.label == EQUAL and j.edits == 0
    assert teacher.judge(pool, (10,), (14,), rng) == Judgement((10,), (14,), RIGHT_BETTER)


def test_equal_answers_are_never_flipped(make_pool):
    pool = make_pool([float(r) for r in range(100)])
    teacher = SimulatedTeacher(Perception(0.0), (EqualWhenClose(0.1), decide, Mistake(1.0)))
    rng = np.random.default_rng(0)
    assert teacher.judge(pool, (10,), (12,), rng).label == EQUAL
    assert teacher.judge(pool, (10,), (50,), rng).label == LEFT_BETTER  # flipped for sure


def test_myopic_teacher_prefers_what_happens_last():
    early = np.zeros(10)
    early[0] = 1.0  # behaviour 0: its whole return at the first step
    late = np.zeros(10)
    late[-1] = 0.8  # behaviour 1: a smaller return, at the last step
    fragments = tuple(
        Fragment(np.zeros((10, 2)), np.zeros((10, 1)), rewards, episode=i, start=0, reset_seed=0)
        for i, rewards in enumerate([early, late])
    )
    pool = BehaviourPool(0, fragments, np.zeros((2, 3)))
    rng = np.random.default_rng(0)
    assert SimulatedTeacher(Perception(0.0)).judge(pool, (0,), (1,), rng).label == LEFT_BETTER
    assert (
        SimulatedTeacher(Perception(0.0, gamma=0.9)).judge(pool, (0,), (1,), rng).label
        == RIGHT_BETTER
    )


def test_default_teacher_pairwise_matches_the_pairwise_rule(make_pool):
    pool = make_pool([float(r) for r in range(20)])
    judgements = Feedback(PairwiseQueries(), SimulatedTeacher(Perception(0.0))).gather(
        pool, 50, np.random.default_rng(0)
    )
    assert len(judgements) == 50 and _error_rate(pool, judgements) == 0.0


def test_teacher_presets_are_built_from_the_parameters():
    p = Imperfection(gamma=0.5, mistake=0.3, skip_quantile=0.2, equal_fraction=0.4)
    assert TEACHERS["myopic"](0.1, p).perception == Perception(0.1, 0.5)
    assert TEACHERS["mistake"](0.1, p).steps == (decide, Mistake(0.3))
    assert TEACHERS["skip"](0.1, p).steps == (SkipWhenBothBelow(0.2), decide)
    assert TEACHERS["equal"](0.1, p).steps == (EqualWhenClose(0.4), decide)


def test_registry_builds_every_decision_maker_and_each_is_seeded(make_pool):
    expected = {"pairwise", "pairwise-boltzmann", "groupwise", "interactive"}
    expected |= {"interactive-mean", "interactive-distinct", "interactive-clear"}
    expected |= {
        f"{dm}-{kind}" for dm in ("pairwise", "groupwise", "interactive") for kind in TEACHERS
    }
    assert set(DECISION_MAKERS) == expected
    pool = make_pool(np.random.default_rng(0).uniform(0, 30, size=40).tolist())
    cfg = RunConfig()
    for name, factory in DECISION_MAKERS.items():
        feedback = factory(cfg)
        first = feedback.gather(pool, 10, np.random.default_rng(3))
        assert len(first) <= 10, name
        assert all(isinstance(j, Judgement) for j in first), name
        assert first == feedback.gather(pool, 10, np.random.default_rng(3)), name
