"""What a round offers from the ensemble's predictions, on hand-checkable numbers."""

import numpy as np

from groupwise.behaviour import TreeNode
from groupwise.server.suggestions import group_suggestions, pairwise_edges, pairwise_queue

# 4 behaviours, 2 members: Var_k[R_k(a) − R_k(b)] = ((d_1 − d_2) / 2)² for differences d_k
RETURNS = np.array([[0.0, 0.0], [1.0, -1.0], [2.0, 2.0], [0.0, 4.0]])
# pair (1, 3): d = (1, -5) → 9; (0, 3): (0, -4) → 4; (2, 3): (2, -2) → 4; (0, 1): 1; …


def test_edges_are_the_most_disputed_pairs_scaled_by_the_best():
    edges = pairwise_edges(RETURNS, 3)
    assert (edges[0].a, edges[0].b, edges[0].score) == ("b1", "b3", 1.0)
    assert {(e.a, e.b) for e in edges[1:]} == {("b0", "b3"), ("b2", "b3")}  # a tie
    assert [e.score for e in edges[1:]] == [4 / 9, 4 / 9]
    assert pairwise_edges(RETURNS, 0) == ()


def test_edges_of_a_certain_ensemble_still_score_in_0_1():
    edges = pairwise_edges(np.ones((3, 2)), 10)
    assert len(edges) == 3 and all(0 < e.score <= 1 for e in edges)


def test_the_pairwise_queue_has_distinct_pairs_in_a_reproducible_order():
    first = pairwise_queue(RETURNS, 6, np.random.default_rng(0))
    again = pairwise_queue(RETURNS, 6, np.random.default_rng(0))
    assert first == again
    assert len({frozenset((p.a, p.b)) for p in first}) == len(first) <= 6
    assert pairwise_queue(RETURNS[:1], 6, np.random.default_rng(0)) == ()


def _node(node_id: str, leaves: tuple[int, ...]) -> TreeNode:
    return TreeNode(node_id, 1, "merge", (), leaves, 1.0)


def test_group_suggestions_pair_disjoint_candidates():
    nodes = (_node("m1", (0, 1)), _node("m2", (2, 3)), _node("m3", (1, 2)))
    suggestions = group_suggestions(RETURNS, np.ones(4), nodes)
    assert suggestions, "two disjoint candidates make at least one suggestion"
    for s in suggestions:
        assert not set(s.left) & set(s.right)
    assert (suggestions[0].left_node, suggestions[0].right_node) == ("m1", "m2")
    assert suggestions[0].left == ("b0", "b1") and suggestions[0].right == ("b2", "b3")
