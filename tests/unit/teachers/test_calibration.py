"""The teacher calibrated to people (`teachers.calibration`): its label error on a pool with
known returns is the one asked for, whatever the pool's scale."""

import math

import numpy as np
import pytest
from tests.unit.teachers.conftest import build_pool

from groupwise.config import RunConfig, TeacherConfig
from groupwise.preferences.judgement import EQUAL
from groupwise.query.strategies import Query
from groupwise.teachers import DECISION_MAKERS, calibration
from groupwise.teachers.calibration import (
    PEOPLE_LABEL_ERROR,
    CalibratedTeacher,
    calibrated_noise_sd,
    pair_error,
)
from groupwise.teachers.group_decision import Perception, SimulatedTeacher
from groupwise.teachers.pairwise import PairwiseTeacher

RETURNS = np.random.default_rng(4).gamma(2.0, 3.0, size=60)  # skewed, as trained pools are


@pytest.mark.parametrize("target", [0.05, PEOPLE_LABEL_ERROR, 0.3])
def test_the_calibrated_noise_gives_the_asked_error(target):
    sd = calibrated_noise_sd(RETURNS, target)
    assert pair_error(RETURNS, sd) == pytest.approx(target, abs=1e-6)
    # the noise is relative to what is compared: a pool 100 times wider, a noise 100 times
    assert calibrated_noise_sd(100 * RETURNS, target) == pytest.approx(100 * sd, rel=1e-6)


def test_a_pool_of_equal_returns_has_nothing_to_get_wrong():
    assert calibrated_noise_sd(np.full(5, 2.0), 0.12) == 0.0
    assert math.isnan(pair_error(np.full(5, 2.0), 1.0))
    with pytest.raises(ValueError, match="label error"):
        calibrated_noise_sd(RETURNS, 0.5)


def _measured_error(teacher, queries: int = 6000) -> float:
    """The teacher's share of wrong labels on random untied pairs of the pool."""
    pool = build_pool(RETURNS.tolist())
    rng = np.random.default_rng(11)
    asked = []
    while len(asked) < queries:
        a, b = rng.choice(len(RETURNS), size=2, replace=False)
        if RETURNS[a] != RETURNS[b]:
            asked.append(Query((int(a),), (int(b),)))
    judgements = teacher.answer(pool, asked, rng)
    wrong = [
        j.label != EQUAL and (j.label == 1.0) != (RETURNS[j.left[0]] > RETURNS[j.right[0]])
        for j in judgements
    ]
    return float(np.mean(wrong))


@pytest.mark.parametrize(
    "make",
    [lambda sigma: PairwiseTeacher(sigma=sigma), lambda sigma: SimulatedTeacher(Perception(sigma))],
    ids=["pairwise", "group-decision"],
)
def test_a_calibrated_teacher_is_wrong_as_often_as_asked(make):
    teacher = CalibratedTeacher(make, PEOPLE_LABEL_ERROR)
    assert abs(_measured_error(teacher) - PEOPLE_LABEL_ERROR) <= 0.02
    # the uncalibrated teacher of SPEC §7 on this pool is another teacher altogether
    assert abs(_measured_error(make(2.0)) - PEOPLE_LABEL_ERROR) > 0.05


def test_every_decision_maker_can_be_calibrated():
    cfg = RunConfig(teacher=TeacherConfig(label_error=PEOPLE_LABEL_ERROR))
    pool = build_pool(RETURNS[:40].tolist())
    for name, factory in DECISION_MAKERS.items():
        feedback = factory(cfg)
        assert isinstance(feedback.teacher, CalibratedTeacher), name
        first = feedback.gather(pool, 8, np.random.default_rng(2))
        assert first == feedback.gather(pool, 8, np.random.default_rng(2)), name


def test_a_pool_is_calibrated_once_for_queries_asked_one_at_a_time(monkeypatch):
    calls = []
    real = calibration.calibrated_noise_sd

    def counted(returns, label_error):
        calls.append(len(returns))
        return real(returns, label_error)

    monkeypatch.setattr(calibration, "calibrated_noise_sd", counted)
    teacher = CalibratedTeacher(lambda sigma: PairwiseTeacher(sigma=sigma), PEOPLE_LABEL_ERROR)
    pool, other = build_pool(RETURNS.tolist()), build_pool(RETURNS[:30].tolist())
    rng = np.random.default_rng(0)
    for _ in range(3):
        teacher.answer(pool, [Query((0,), (1,))], rng)
    teacher.answer(other, [Query((0,), (1,))], rng)
    assert calls == [60, 30]
