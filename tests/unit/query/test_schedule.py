import pytest

from groupwise.query.schedule import comparisons_per_round


def test_constant_schedule_by_hand():
    assert comparisons_per_round(100, 5) == [10, 23, 23, 22, 22]


@pytest.mark.parametrize("schedule", ["constant", "hyperbolic", "inverse_quadratic"])
@pytest.mark.parametrize(("total", "rounds"), [(1, 1), (7, 3), (400, 10), (3, 8)])
def test_every_schedule_sums_to_the_total(schedule, total, rounds):
    counts = comparisons_per_round(total, rounds, 0.1, schedule)
    assert len(counts) == rounds and sum(counts) == total and min(counts) >= 0


def test_hyperbolic_decreases():
    counts = comparisons_per_round(400, 5, 0.1, "hyperbolic")
    assert counts[1] > counts[2] > counts[3] > counts[4]


def test_bad_arguments():
    with pytest.raises(ValueError, match="schedule"):
        comparisons_per_round(10, 2, 0.1, "sometimes")
    with pytest.raises(ValueError):
        comparisons_per_round(0, 2)
