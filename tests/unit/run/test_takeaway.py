"""The take-away choice: the round whose episodes the teacher prefers (issue 20)."""

import math
from collections.abc import Sequence

import numpy as np
import pytest

from groupwise.behaviour.pool import BehaviourPool
from groupwise.episodes.fragments import Trajectory
from groupwise.preferences.judgement import Judgement
from groupwise.query.strategies import Query
from groupwise.run.takeaway import (
    TakeawayConfig,
    choose_round,
    preferred,
    read_choice,
    write_choice,
)
from groupwise.teachers.base import Teacher
from groupwise.teachers.calibration import CalibratedTeacher
from groupwise.teachers.group_decision import Perception, SimulatedTeacher
from groupwise.teachers.pairwise import PairwiseTeacher


def episode(total: float, seed: int = 0, steps: int = 10) -> Trajectory:
    """An episode whose true return is `total`, spread evenly over its steps."""
    return Trajectory(
        obs=np.zeros((steps, 2)),
        acts=np.zeros((steps, 1)),
        actions=np.zeros((steps, 1)),
        true_rewards=np.full(steps, total / steps),
        reset_seed=seed,
        episode=0,
    )


def rounds_of(returns: dict[int, Sequence[float]]) -> dict[int, list[Trajectory]]:
    return {r: [episode(v, seed=e) for e, v in enumerate(vs)] for r, vs in returns.items()}


def test_a_noise_free_teacher_picks_the_round_it_prefers():
    # round 2 is the best: a walker that held its split after round 2 and lost it after
    episodes = rounds_of({0: [1, 2, 1], 1: [3, 2, 4], 2: [9, 8, 9], 3: [2, 3, 1]})
    for teacher in (PairwiseTeacher(sigma=0.0), SimulatedTeacher(Perception(0.0))):
        choice = choose_round(episodes, teacher, np.random.default_rng(0))
        assert choice.round == 2
        assert choice.by == "teacher"
        assert choice.rounds == (0, 1, 2, 3)
        # round 2 wins all of its 3 × 3 comparisons, round 0 loses all but a 2-vs-2 tie
        assert choice.scores[2] == 1.0
        assert len(choice.verdicts) == 6 * 3
        assert choice.returns == pytest.approx((4 / 3, 3, 26 / 3, 2))


def test_ties_go_to_the_later_round():
    episodes = rounds_of({0: [5, 5], 1: [5, 5], 2: [1, 1]})
    choice = choose_round(episodes, PairwiseTeacher(sigma=0.0), np.random.default_rng(0))
    assert choice.scores == pytest.approx((0.75, 0.75, 0.0))
    assert choice.round == 1
    assert preferred((0, 1, 2), (0.5, 0.5, 0.5)) == 2
    assert preferred((0, 1, 2), (math.nan, math.nan, math.nan)) == 2  # nothing judged: the last
    assert preferred((0, 1, 2), (0.9, math.nan, 0.1)) == 0


class PrefersRound:
    """A teacher that prefers the episodes of one round (by its episodes' reset seeds)."""

    def __init__(self, seeds: set[int]) -> None:
        self.seeds = seeds

    def answer(
        self, pool: BehaviourPool, queries: Sequence[Query], rng: np.random.Generator
    ) -> list[Judgement]:
        out = []
        for q in queries:
            left = pool.fragments[q.left[0]].reset_seed in self.seeds
            right = pool.fragments[q.right[0]].reset_seed in self.seeds
            label = 0.5 if left == right else 1.0 if left else 0.0
            out.append(Judgement(q.left, q.right, label))
        return out


def test_a_teacher_that_prefers_round_k_picks_k_whatever_the_returns():
    episodes = {
        r: [
            Trajectory(
                obs=np.zeros((4, 1)),
                acts=np.zeros((4, 1)),
                actions=np.zeros((4, 1)),
                true_rewards=np.full(4, float(r)),  # the true return favours the last round
                reset_seed=100 * r + e,
                episode=e,
            )
            for e in range(2)
        ]
        for r in range(4)
    }
    teacher: Teacher = PrefersRound({100, 101})  # round 1's episodes
    choice = choose_round(episodes, teacher, np.random.default_rng(0))
    assert choice.round == 1
    assert choice.scores[1] == 1.0


def test_skipped_comparisons_count_for_nobody():
    class Skips:
        def answer(self, pool, queries, rng):
            return []

    choice = choose_round(rounds_of({0: [1], 1: [2]}), Skips(), np.random.default_rng(0))
    assert [v.label for v in choice.verdicts] == [None]
    assert all(math.isnan(s) for s in choice.scores)
    assert choice.round == 1


def test_a_noisy_teacher_is_seeded_and_mostly_right(tmp_path):
    episodes = rounds_of({r: [r + 0.3 * e for e in range(3)] for r in range(5)})
    teacher = CalibratedTeacher(lambda sigma: PairwiseTeacher(sigma=sigma), 0.12)
    first = choose_round(episodes, teacher, np.random.default_rng(7))
    again = choose_round(episodes, teacher, np.random.default_rng(7))
    assert first == again
    wrong = [
        v.label != (1.0 if v.left > v.right else 0.0) for v in first.verdicts if v.label is not None
    ]
    assert np.mean(wrong) < 0.3
    assert first.round >= 3
    write_choice(tmp_path, first, TakeawayConfig(episodes=3))
    assert read_choice(tmp_path) == first
    assert read_choice(tmp_path / "none") is None


def test_one_round_is_chosen_without_asking():
    class Never:
        def answer(self, pool, queries, rng):
            raise AssertionError("asked")

    assert choose_round(rounds_of({3: [1.0]}), Never(), np.random.default_rng(0)).round == 3
    with pytest.raises(ValueError):
        choose_round({}, Never(), np.random.default_rng(0))
    with pytest.raises(ValueError):
        TakeawayConfig(episodes=0)
