import numpy as np

from groupwise.query.pairwise import pair_scores, random_pairs, select_pairs, top_pairs

# three behaviours, two members: members agree on 0 vs 1 (difference 1 both times) and
# disagree most on 0 vs 2 (differences -2 and +2)
RETURNS = np.array([[0.0, 0.0], [-1.0, -1.0], [2.0, -2.0]])


def test_pair_scores_by_hand():
    scores = pair_scores(RETURNS, np.array([[0, 1], [0, 2], [1, 2]]))
    # Var of (1, 1) = 0; Var of (-2, 2) = 4; Var of (-3, 1) = 4
    np.testing.assert_allclose(scores, [0.0, 4.0, 4.0])


def test_random_pairs_are_distinct():
    pairs = random_pairs(5, 1000, np.random.default_rng(0))
    assert (pairs[:, 0] != pairs[:, 1]).all() and pairs.max() < 5


def test_select_pairs_takes_the_most_disputed_candidate():
    pairs = select_pairs(RETURNS, n_queries=20, n_candidates=50, rng=np.random.default_rng(1))
    assert all(2 in pair for pair in pairs.tolist())


def test_top_pairs_sorted_best_first():
    pairs, scores = top_pairs(RETURNS, 2)
    assert scores.tolist() == [4.0, 4.0]
    assert {tuple(sorted(p)) for p in pairs.tolist()} == {(0, 2), (1, 2)}
