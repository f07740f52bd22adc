import numpy as np
import pytest

from groupwise.preferences.judgement import EQUAL, LEFT_BETTER, RIGHT_BETTER
from groupwise.teachers.group_decision import (
    Perception,
    SimulatedTeacher,
    decide,
    group_decision,
)

LEFT = (5, 6, 7)
RIGHT = (8, 9)


def test_clear_win_keeps_everyone():
    # means 11 and 2, midpoint 6.5: nobody on the wrong side
    d = group_decision(LEFT[:2], RIGHT, np.array([10.0, 12.0]), np.array([1.0, 3.0]))
    assert d is not None
    assert (d.left, d.right, d.label, d.removed) == ((5, 6), (8, 9), LEFT_BETTER, 0)


def test_right_group_can_win():
    d = group_decision(LEFT[:2], RIGHT, np.array([1.0, 3.0]), np.array([10.0, 12.0]))
    assert d is not None and d.label == RIGHT_BETTER and d.removed == 0


def test_significant_interference_skips():
    # left mean 10/3, right mean 2, midpoint 8/3: two of three left members are below it
    assert group_decision(LEFT, RIGHT, np.array([10.0, 0.0, 0.0]), np.array([2.0, 2.0])) is None
    # the same on the losing side: right mean 4 over a left mean of 5 ... midpoint 4.5,
    # right members 0.5 and 7.5 -> one of two above: not more than half, kept
    d = group_decision((1,), (2, 3), np.array([5.0]), np.array([0.5, 7.5]))
    assert d is not None and d.right == (2,) and d.removed == 1


def test_outliers_on_both_sides_are_removed():
    # left (10, 12, 0) mean 22/3, right (1, 3, 6) mean 10/3, midpoint 16/3:
    # left's 0 is below it and right's 6 above it, one of three each -> both removed
    d = group_decision(LEFT, (8, 9, 4), np.array([10.0, 12.0, 0.0]), np.array([1.0, 3.0, 6.0]))
    assert d is not None
    assert (d.left, d.right, d.label, d.removed) == ((5, 6), (8, 9), LEFT_BETTER, 2)


def test_a_member_exactly_at_the_midpoint_counts_as_wrong():
    # left (6, 2) mean 4, right (0,) mean 0, midpoint 2: the 2 is no better than b
    d = group_decision((1, 2), (3,), np.array([6.0, 2.0]), np.array([0.0]))
    assert d is not None and d.left == (1,) and d.removed == 1


def test_equal_means():
    everyone_alike = group_decision((1, 2), (3,), np.array([4.0, 4.0]), np.array([4.0]))
    assert everyone_alike is not None and everyone_alike.label == EQUAL
    assert everyone_alike.removed == 0
    # equal means but differing members: no winner, no outliers to tell -> skipped
    assert group_decision((1, 2), (3,), np.array([2.0, 6.0]), np.array([4.0])) is None


def test_pairs_follow_the_higher_perceived_return():
    for a, b in [(1.0, 0.0), (-3.0, 2.0)]:
        d = group_decision((0,), (1,), np.array([a]), np.array([b]))
        assert d is not None and d.label == (LEFT_BETTER if a > b else RIGHT_BETTER)
    tie = group_decision((0,), (1,), np.array([1.0]), np.array([1.0]))
    assert tie is not None and tie.label == EQUAL


def test_mismatched_inputs_raise():
    with pytest.raises(ValueError):
        group_decision((1, 2), (3,), np.array([1.0]), np.array([0.0]))


def test_myopic_perception_discounts_earlier_steps(make_pool):
    pool = make_pool([3.0, 0.0])  # behaviour 0: reward 0.3 on each of 10 steps
    seen = Perception(sigma=0.0, gamma=0.5)(pool, [0, 1], np.random.default_rng(0))
    expected = 0.3 * sum(0.5**t for t in range(10))
    np.testing.assert_allclose(seen, [expected, 0.0])
    exact = Perception(sigma=0.0)(pool, [0, 1], np.random.default_rng(0))
    np.testing.assert_allclose(exact, pool.true_returns)


def test_teacher_judges_with_noise_free_perception(make_pool):
    pool = make_pool([10.0, 12.0, 0.0, 1.0, 3.0, 6.0])
    teacher = SimulatedTeacher(Perception(sigma=0.0))
    j = teacher.judge(pool, (0, 1, 2), (3, 4, 5), np.random.default_rng(0))
    assert j is not None
    assert (j.left, j.right, j.label, j.edits) == ((0, 1), (3, 4), LEFT_BETTER, 2)
    assert teacher.judge(pool, (0, 2, 3), (4,), np.random.default_rng(0)) is None


def test_a_teacher_without_a_decision_step_raises(make_pool):
    pool = make_pool([1.0, 0.0])
    with pytest.raises(ValueError):
        SimulatedTeacher(Perception(0.0), steps=()).judge(
            pool, (0,), (1,), np.random.default_rng(0)
        )
    assert decide  # the step every teacher needs
