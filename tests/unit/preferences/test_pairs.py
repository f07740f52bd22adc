import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from groupwise.preferences.judgement import EQUAL, LEFT_BETTER, Judgement
from groupwise.preferences.pairs import (
    Pair,
    cap_pairs,
    cartesian_pairs,
    covering_pairs,
    oversample_pairs,
)


@given(
    m=st.integers(1, 12),
    n=st.integers(1, 12),
    label=st.sampled_from([0.0, 0.5, 1.0]),
    seed=st.integers(0, 2**32 - 1),
)
def test_covering_pairs_use_every_member_and_max_m_n_pairs(m, n, label, seed):
    left = tuple(range(m))
    right = tuple(range(100, 100 + n))
    pairs = covering_pairs(Judgement(left, right, label), np.random.default_rng(seed))
    assert len(pairs) == max(m, n)
    assert {p.a for p in pairs} == set(left)
    assert {p.b for p in pairs} == set(right)
    assert all(p.label == label for p in pairs)
    # the larger group appears exactly once per member
    larger = [p.a for p in pairs] if m >= n else [p.b for p in pairs]
    assert len(set(larger)) == len(larger)


def test_covering_pairs_are_reproducible_from_the_seed():
    judgement = Judgement((1, 2, 3), (4, 5), LEFT_BETTER)
    first = covering_pairs(judgement, np.random.default_rng(3))
    again = covering_pairs(judgement, np.random.default_rng(3))
    assert first == again


def test_cartesian_pairs_are_all_m_times_n():
    pairs = cartesian_pairs(Judgement((1, 2), (3, 4, 5), EQUAL), np.random.default_rng(0))
    assert len(pairs) == 6 and all(p.label == 0.5 for p in pairs)


@pytest.mark.parametrize(
    ("left", "right", "label", "message"),
    [
        ((), (1,), 1.0, "at least one"),
        ((1, 2), (2, 3), 1.0, "in both groups"),
        ((1, 1), (2,), 1.0, "twice"),
        ((1,), (2,), 0.7, "label"),
    ],
)
def test_invalid_judgements_are_rejected(left, right, label, message):
    with pytest.raises(ValueError, match=message):
        Judgement(left, right, label)


@given(count=st.integers(0, 30), limit=st.integers(0, 40), seed=st.integers(0, 2**32 - 1))
def test_cap_pairs_keeps_at_most_the_limit_in_order(count, limit, seed):
    pairs = [Pair(i, i + 100, 1.0) for i in range(count)]
    kept = cap_pairs(pairs, limit, np.random.default_rng(seed))
    assert len(kept) == min(count, limit)
    assert len(set(kept)) == len(kept)
    assert kept == sorted(kept)  # the original order
    assert set(kept) <= set(pairs)


def test_cap_pairs_rejects_a_negative_limit():
    with pytest.raises(ValueError, match="limit"):
        cap_pairs([], -1, np.random.default_rng(0))


def test_oversampling_by_one_is_the_derivation_itself():
    judgement = Judgement((1, 2, 3), (4, 5), LEFT_BETTER)
    rng, same = np.random.default_rng(7), np.random.default_rng(7)
    assert oversample_pairs(judgement, covering_pairs, 1.0, rng) == covering_pairs(judgement, same)
    assert rng.random() == same.random()  # and it drew no more numbers


@given(m=st.integers(1, 8), n=st.integers(1, 8), seed=st.integers(0, 2**32 - 1))
def test_oversampling_by_two_gives_twice_the_covering_pairs(m, n, seed):
    left, right = tuple(range(m)), tuple(range(100, 100 + n))
    judgement = Judgement(left, right, LEFT_BETTER)
    pairs = oversample_pairs(judgement, covering_pairs, 2.0, np.random.default_rng(seed))
    assert len(pairs) == 2 * max(m, n)
    # each half is a covering draw of its own
    for half in (pairs[: max(m, n)], pairs[max(m, n) :]):
        assert {p.a for p in half} == set(left) and {p.b for p in half} == set(right)


def test_oversampling_rounds_the_count_and_repeats_a_single_pair():
    three = Judgement((1, 2, 3), (4,), LEFT_BETTER)
    assert len(oversample_pairs(three, covering_pairs, 1.5, np.random.default_rng(0))) == 5
    single = Judgement((1,), (2,), LEFT_BETTER)
    twice = oversample_pairs(single, covering_pairs, 2.0, np.random.default_rng(0))
    assert twice == [Pair(1, 2, 1.0), Pair(1, 2, 1.0)]


def test_oversampling_rejects_a_factor_below_one():
    with pytest.raises(ValueError, match="factor"):
        oversample_pairs(
            Judgement((1,), (2,), EQUAL), covering_pairs, 0.5, np.random.default_rng(0)
        )
