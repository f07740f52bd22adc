"""A round's offer as the page shows it, on hand-checkable numbers."""

import numpy as np
from scipy.spatial.distance import pdist

from groupwise.behaviour import build_tree
from groupwise.config import TreeConfig
from groupwise.query.strategies import Query
from groupwise.worker.offers import pairwise_edges, queries_as_rows

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


def _tree():
    """Two tight pairs far apart: {0, 1} and {2, 3} are the level-1 nodes."""
    points = np.array([[0.0], [0.1], [10.0], [10.1]])
    return build_tree(pdist(points), TreeConfig(levels=2, bands="linear"))


def test_queries_keep_their_order_and_name_their_tree_nodes():
    tree = _tree()
    node = {frozenset(n.leaves): n.id for n in tree.nodes() if n.kind != "padding"}
    queries = [Query((2, 3), (0, 1)), Query((1,), (3,)), Query((0, 2), (1, 3))]
    groups, pairs = queries_as_rows(queries, tree, RETURNS)
    # the mixed groups {0, 2} / {1, 3} are no tree node: not a suggestion
    assert [(g.left, g.right) for g in groups] == [(("b2", "b3"), ("b0", "b1")), (("b1",), ("b3",))]
    assert groups[0].left_node == node[frozenset((2, 3))]
    assert groups[1].left_node == "b1" and groups[1].right_node == "b3"
    # the pair is the pairwise queue too, scored by the ensemble's disagreement (9 above)
    assert [(p.a, p.b, p.score) for p in pairs] == [("b1", "b3", 9.0)]
    difference = RETURNS[[2, 3]].mean(axis=0) - RETURNS[[0, 1]].mean(axis=0)
    assert groups[0].score == float(np.var(difference))
