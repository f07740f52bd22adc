import numpy as np
import pytest

from groupwise.query.groups import (
    INTRA_FLOOR,
    GroupCandidate,
    pair_variance_matrix,
    return_variance,
    score_group_pairs,
    step_variance,
    suggest_groups,
    suggestion_order,
)
from groupwise.query.pairwise import pair_scores

# four behaviours, two members. With s(f) = R_1(f) - R_2(f) = (0, 2, -4, 0),
# Var_k[R_k(a) - R_k(b)] = (s_a - s_b)^2 / 4:
#   V01 = 1, V02 = 4, V03 = 0, V12 = 9, V13 = 1, V23 = 4
RETURNS = np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 4.0], [1.0, 1.0]])
INTRA = np.array([1.0, 1.0, 4.0, 0.0])
A = GroupCandidate("a", (0, 1))
B = GroupCandidate("b", (2, 3))
C = GroupCandidate("c", (3,))
D = GroupCandidate("d", (2,))
CANDIDATES = [A, B, C, D]
# disjoint pairs (candidate rows): AB (0, 1), AC (0, 2), AD (0, 3), CD (2, 3); B shares
# behaviour 3 with C and 2 with D.
#   inter: AB = (4 + 0 + 9 + 1) / 4 = 3.5, AC = (0 + 1) / 2 = 0.5, AD = (4 + 9) / 2 = 6.5,
#          CD = V23 = 4                                            -> max 6.5
#   intra per group: A = 1, B = 2, C = 0, D = 4
#   intra per pair:  AB = 2, AC = 1, AD = 4, CD = 4                 -> max 4
#   size penalty:    AB = 1, AC = 4/3, AD = 4/3, CD = 1
#   score: AB = (3.5/6.5) / (2/4) = 14/13, AC = (0.5/6.5) / (1/4) / (4/3) = 3/13,
#          AD = 1 / 1 / (4/3) = 3/4,    CD = (4/6.5) / 1 = 8/13
EXPECTED = {"ab": 14 / 13, "ac": 3 / 13, "ad": 3 / 4, "cd": 8 / 13}


def _by_name(scores):
    names = ["".join(CANDIDATES[i].id for i in pair) for pair in scores.pairs.tolist()]
    return dict(zip(names, scores.score.tolist(), strict=True))


def test_pair_variance_matrix_by_hand_and_agrees_with_pair_scores():
    v = pair_variance_matrix(RETURNS)
    np.testing.assert_allclose(v[0], [0, 1, 4, 0])
    np.testing.assert_allclose(v[1, 2:], [9, 1])
    np.testing.assert_allclose(v[2, 3], 4)
    np.testing.assert_allclose(v, v.T)
    rng = np.random.default_rng(0)
    returns = rng.normal(size=(12, 5))
    i, j = np.triu_indices(12, k=1)
    pairs = np.stack([i, j], axis=1)
    np.testing.assert_allclose(pair_variance_matrix(returns)[i, j], pair_scores(returns, pairs))


def test_group_variance_score_by_hand():
    scores = score_group_pairs(RETURNS, INTRA, CANDIDATES)
    assert scores.pairs.tolist() == [[0, 1], [0, 2], [0, 3], [2, 3]]
    np.testing.assert_allclose(scores.inter, [3.5, 0.5, 6.5, 4.0])
    np.testing.assert_allclose(scores.intra, [2.0, 1.0, 4.0, 4.0])
    np.testing.assert_allclose(scores.size_penalty, [1.0, 4 / 3, 4 / 3, 1.0])
    got = _by_name(scores)
    assert got.keys() == EXPECTED.keys()
    for name, value in EXPECTED.items():
        assert got[name] == pytest.approx(value)


def test_suggestions_best_first_each_node_at_most_twice():
    # by score: AB, AD, CD, AC; AC is dropped because A is already in two suggestions
    suggestions = suggest_groups(RETURNS, INTRA, CANDIDATES, count=10)
    assert [(s.left.id, s.right.id) for s in suggestions] == [("a", "b"), ("a", "d"), ("c", "d")]
    assert [s.score for s in suggestions] == pytest.approx([14 / 13, 3 / 4, 8 / 13])
    assert len(suggest_groups(RETURNS, INTRA, CANDIDATES, count=2)) == 2


def test_suggestion_order_with_one_use_and_refill():
    scores = score_group_pairs(RETURNS, INTRA, CANDIDATES)
    # rows: AB 0, AC 1, AD 2, CD 3
    assert suggestion_order(scores, 10, max_uses=1).tolist() == [0, 3]
    # refill: the next list over AD, AC takes AD (AC shares A), then a third list takes AC
    assert suggestion_order(scores, 10, max_uses=1, refill=True).tolist() == [0, 3, 2, 1]
    assert suggestion_order(scores, 3, max_uses=1, refill=True).tolist() == [0, 3, 2]


def test_zero_maxima_give_finite_scores():
    flat = np.ones((4, 2))  # the members agree everywhere: every inter is 0
    scores = score_group_pairs(flat, INTRA, CANDIDATES)
    assert np.isfinite(scores.score).all() and (scores.score == 0).all()
    certain = score_group_pairs(RETURNS, np.zeros(4), CANDIDATES)  # every intra is 0
    np.testing.assert_allclose(certain.score, (certain.inter / 6.5) / certain.size_penalty)
    # a pair of two groups the ensemble is sure of (intra 0) among others: the floor keeps
    # its score finite, and on top
    lone = score_group_pairs(RETURNS, np.array([0.0, 0.0, 0.0, 1.0]), [A, D, C])
    assert np.isfinite(lone.score).all()
    np.testing.assert_allclose(lone.intra, [0.0, 1.0, 1.0])  # AD, AC, DC
    assert lone.score[0] == pytest.approx(1.0 / INTRA_FLOOR / (4 / 3))
    assert lone.score.argmax() == 0


def test_fewer_than_two_candidates_or_no_disjoint_pair():
    assert len(score_group_pairs(RETURNS, INTRA, [A])) == 0
    assert suggest_groups(RETURNS, INTRA, [B, C], count=5) == []


def test_step_variance_is_the_member_variance_averaged_over_steps():
    # one behaviour, two steps: members say (0, 2) and (2, 2) -> per-step variances 1 and 0
    step = np.array([[[0.0, 2.0]], [[2.0, 2.0]]])  # (K=2, N=1, L=2)
    np.testing.assert_allclose(step_variance(step), [0.5])  # not 0.75, the variance of all four
    with pytest.raises(ValueError):
        step_variance(np.zeros((2, 3)))


def test_return_variance_fallback():
    np.testing.assert_allclose(return_variance(np.array([[2.0, 4.0]]), length=2), [0.5])


def test_candidates_are_validated():
    with pytest.raises(ValueError):
        GroupCandidate("x", ())
    with pytest.raises(ValueError):
        GroupCandidate("x", (1, 1))
    with pytest.raises(ValueError):
        score_group_pairs(RETURNS, INTRA, [A, GroupCandidate("far", (7,))])
