import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.cluster.hierarchy import leaves_list, linkage
from scipy.spatial.distance import pdist, squareform

from groupwise.behaviour import (
    BehaviourTree,
    TreeConfig,
    TreeNode,
    assign_levels,
    build_tree,
    count_thresholds,
    from_json,
    geometric_thresholds,
    group_candidates,
    linear_thresholds,
    medoids,
    to_json,
)
from groupwise.behaviour.balance import indistinguishable_spread, level_caps

# six points on a line; complete linkage merges (0,1)@1 -> m6, (4,5)@1 -> m7,
# (2,m6)@3 -> m8, (3,m8)@7 -> m9, (m7,m9)@16 -> root. D = 16, thresholds 4, 8, 12, 16.
LINE = np.array([0.0, 1.0, 3.0, 7.0, 15.0, 16.0])
LINEAR = TreeConfig(bands="linear", balance=None)
"""The paper's cut, which the hand-worked trees below were drawn for (no size caps)."""

LINE_D = pdist(LINE[:, None])


def shape(node: TreeNode) -> tuple:
    """(id, level, children shapes) or the leaf's id."""
    if node.kind == "leaf":
        return node.id
    return (node.id, node.level, [shape(c) for c in node.children])


def check_invariants(tree: BehaviourTree, n: int) -> None:
    ids = [node.id for node in tree.nodes()]
    assert len(ids) == len(set(ids))
    assert tree.root.id == "root" and tree.root.level == tree.levels
    assert sorted(tree.root.leaves) == list(range(n))
    for node in tree.nodes():
        assert node.size == len(node.leaves)
        if node.kind == "leaf":
            assert node.level == 0 and node.children == ()
            continue
        # padding keeps every edge one level long, so every leaf is at depth `levels`
        assert all(c.level == node.level - 1 for c in node.children)
        assert node.leaves == tuple(i for c in node.children for i in c.leaves)
        assert len(node.children) == 1 if node.kind == "padding" else len(node.children) >= 1
    leaves = [node for node in tree.nodes() if node.kind == "leaf"]
    assert [leaf.behaviour for leaf in leaves] == list(tree.leaf_order)


def check_caps(
    tree: BehaviourTree, d: np.ndarray, balance: float, top_balance: float | None = 1.25
) -> None:
    """Every node below the root holds at most its level's cap, or is a level >= 2 node of
    indistinguishable behaviours (`balance.balance_levels`)."""
    n = tree.root.size
    if n < 4 or tree.levels < 2:
        return
    square = squareform(d)
    floor = indistinguishable_spread(d)
    caps = level_caps(n, tree.levels, balance, top_balance)
    for node in tree.nodes():
        if 1 <= node.level < tree.levels and node.size > caps[node.level - 1]:
            idx = np.array(node.leaves)
            spread = square[np.ix_(idx, idx)].sum() / (len(idx) * (len(idx) - 1))
            assert node.level >= 2 and spread <= floor, (node.id, node.size)


def test_line_tree_by_hand():
    tree = build_tree(LINE_D, LINEAR)
    assert tree.thresholds == (4.0, 8.0, 12.0, 16.0)
    # m6 (level 1) under m8 (level 1) is dissolved: b0, b1 take its place after b2
    assert shape(tree.root) == (
        "root",
        4,
        [
            ("m7@3", 3, [("m7@2", 2, [("m7", 1, ["b4", "b5"])])]),
            ("m9@3", 3, [("m9", 2, [("b3@1", 1, ["b3"]), ("m8", 1, ["b2", "b0", "b1"])])]),
        ],
    )
    assert tree.leaf_order == (4, 5, 3, 2, 0, 1)
    assert tree.leaf_order == tuple(leaves_list(linkage(LINE_D, "complete")))
    assert tree.node("m8").height == 3.0 and tree.node("m7@2").kind == "padding"
    assert tree.parent("m8") is tree.node("m9") and tree.parent("root") is None
    assert [n.id for n in tree.at_level(1)] == ["m7", "b3@1", "m8"]
    check_invariants(tree, 6)


def test_dissolved_merges_splice_in_place():
    # (0,1)@1 and (2,3)@1 sit under a merge @3.5; D = 20 puts all three at level 1, so
    # both dissolve and their leaves become the children of the @3.5 merge, in order
    x = np.array([0.0, 1.0, 2.5, 3.5, 20.0])
    d = pdist(x[:, None])
    tree = build_tree(d, LINEAR)
    order = tuple(int(i) for i in leaves_list(linkage(d, "complete")))
    level1 = [n for n in tree.at_level(1) if n.kind == "merge"]
    assert [n.leaves for n in level1] == [tuple(i for i in order if i < 4)]
    assert [c.id for c in level1[0].children] == [f"b{i}" for i in order if i < 4]
    check_invariants(tree, 5)


def test_merge_at_an_exact_threshold_goes_one_level_up():
    # (0,1)@1 and (3,4)@1 with D = 4: t_1 = 1 does not exceed 1, so both are level 2
    tree = build_tree(pdist(np.array([[0.0], [1.0], [3.0], [4.0]])), LINEAR)
    assert tree.thresholds == (1.0, 2.0, 3.0, 4.0)
    merges = [n for n in tree.nodes() if n.kind == "merge" and n.id != "root"]
    assert [(n.level, n.leaves) for n in merges] == [(2, (0, 1)), (2, (2, 3))]
    assert assign_levels(
        np.array([0.0, 0.999, 1.0, 2.5, 3.0, 4.0]), (1.0, 2.0, 3.0, 4.0)
    ).tolist() == [
        1,
        1,
        2,
        3,
        4,
        4,
    ]
    check_invariants(tree, 4)


def test_threshold_bands():
    assert linear_thresholds(np.array([1.0, 16.0]), 4) == (4.0, 8.0, 12.0, 16.0)
    assert geometric_thresholds(np.array([16.0]), 4) == (2.0, 4.0, 8.0, 16.0)
    assert (
        linear_thresholds(np.array([0.1, 0.3]), 3)[-1] == 0.3
    )  # the top is exactly the root height
    tree = build_tree(LINE_D, TreeConfig(bands="geometric", balance=None))
    assert tree.thresholds == (2.0, 4.0, 8.0, 16.0)
    assert tree.node("m8").level == 2 and tree.node("m9").level == 3
    check_invariants(tree, 6)


def test_group_candidates():
    tree = build_tree(LINE_D, LINEAR)
    # pre-order; the padding m7@2 repeats m7's leaves and is left out
    assert [n.id for n in group_candidates(tree)] == ["m7", "m9", "m8"]
    assert [n.id for n in group_candidates(tree, max_size=3)] == ["m7", "m8"]
    assert [n.id for n in group_candidates(tree, levels=(2,))] == ["m9"]
    assert [n.id for n in group_candidates(tree, min_size=3)] == ["m9", "m8"]


def test_medoids():
    tree = build_tree(LINE_D, LINEAR)
    # m8 holds points 3 (b2), 0 (b0), 1 (b1): summed distances 5, 4, 3
    assert medoids(tree.node("m8"), LINE_D) == (1, 0, 2)
    assert medoids(tree.node("m8"), squareform(LINE_D), k=2) == (1, 0)
    assert medoids(tree.node("b3"), LINE_D) == (3,)
    assert len(medoids(tree.root, LINE_D, k=3)) == 3


@pytest.mark.parametrize("n", [1, 2, 5])
def test_degenerate_pools_give_valid_trees(n):
    tree = build_tree(np.zeros(n * (n - 1) // 2))  # n identical behaviours: root height 0
    check_invariants(tree, n)
    assert tree.thresholds == (0.0, 0.0, 0.0, 0.0)
    assert [c.id for c in tree.root.children] == [f"b{i}@3" for i in tree.leaf_order]
    assert group_candidates(tree) == []


def test_two_behaviours():
    tree = build_tree(np.array([2.5]), TreeConfig(levels=2))
    assert shape(tree.root) == ("root", 2, [("b0@1", 1, ["b0"]), ("b1@1", 1, ["b1"])])


def test_long_chain_does_not_recurse():
    x = 2.0 ** np.arange(300)  # complete linkage adds one point per merge
    tree = build_tree(pdist(x[:, None]), LINEAR)
    check_invariants(tree, 300)


def test_json_round_trip():
    tree = build_tree(LINE_D, LINEAR)
    payload = to_json(tree, leaf_extra={4: {"clip": "/clips/4.mp4"}})
    text = json.dumps(payload)
    back = json.loads(text)
    assert back["format"] == "groupwise.behaviour-tree/1"
    assert back["levels"] == 4 and back["thresholds"] == [4.0, 8.0, 12.0, 16.0]
    assert back["leaf_order"] == [4, 5, 3, 2, 0, 1]
    root = back["root"]
    assert (root["id"], root["level"], root["size"]) == ("root", 4, 6)
    leaf = root["children"][0]["children"][0]["children"][0]["children"][0]
    assert leaf == {
        "id": "b4",
        "kind": "leaf",
        "level": 0,
        "height": 0.0,
        "size": 1,
        "leaves": [4],
        "children": [],
        "behaviour": 4,
        "extra": {"clip": "/clips/4.mp4"},
    }
    assert from_json(back) == tree
    by_callback = to_json(tree, leaf_extra=lambda i: {"poster": f"/p/{i}.png"})
    assert by_callback["root"]["children"][1]["children"][0]["children"][0]["children"][0][
        "extra"
    ] == {"poster": "/p/3.png"}


def test_invalid_inputs():
    with pytest.raises(ValueError):
        TreeConfig(levels=0)
    with pytest.raises(ValueError):
        TreeConfig(method="single")
    with pytest.raises(ValueError):
        TreeConfig(bands="log")
    with pytest.raises(ValueError):
        build_tree(np.array([1.0, 2.0]))  # not N (N - 1) / 2 distances
    with pytest.raises(ValueError):
        build_tree(np.array([-1.0]))


@settings(max_examples=60, deadline=None)
@given(
    n=st.integers(1, 24),
    seed=st.integers(0, 2**32 - 1),
    method=st.sampled_from(["complete", "average", "ward"]),
    bands=st.sampled_from(["counts", "linear", "geometric"]),
    levels=st.integers(1, 5),
    ties=st.booleans(),
    balance=st.sampled_from([None, 1.0, 2.0]),
    top_balance=st.sampled_from([None, 1.0, 1.25]),
)
def test_tree_properties(n, seed, method, bands, levels, ties, balance, top_balance):
    rng = np.random.default_rng(seed)
    d = rng.random(n * (n - 1) // 2) * 10
    if ties:  # few distinct values: equal heights and merges exactly at thresholds
        d = np.round(d / 2.5) * 2.5
    cfg = TreeConfig(
        levels=levels, method=method, bands=bands, balance=balance, top_balance=top_balance
    )
    tree = build_tree(d, cfg)
    check_invariants(tree, n)
    if n >= 2:
        assert tree.leaf_order == tuple(int(i) for i in leaves_list(linkage(d, method)))
        t = (0.0, *tree.thresholds)
        for node in tree.nodes():
            if node.kind == "merge" and node.level < levels and balance is None:
                assert t[node.level - 1] <= node.height < t[node.level]
        if balance is not None:
            check_caps(tree, d, balance, top_balance)
    assert from_json(json.loads(json.dumps(to_json(tree)))) == tree


def test_pool_to_tree_end_to_end():
    from groupwise.behaviour import dtw_matrix, pool_features
    from groupwise.episodes.fragments import Fragment

    rng = np.random.default_rng(5)
    fragments = [
        Fragment(
            obs=rng.normal(size=(30, 11)) * 10 + i % 3,
            acts=rng.uniform(-1, 1, size=(30, 3)),
            true_rewards=np.zeros(30),
            episode=i,
            start=0,
            reset_seed=i,
        )
        for i in range(40)
    ]
    distances = dtw_matrix(pool_features(fragments), window=5)
    tree = build_tree(distances, TreeConfig(method="average"))
    check_invariants(tree, 40)
    for node in group_candidates(tree):
        assert 2 <= node.size <= 8 and node.level in (1, 2)
        assert set(medoids(node, distances)) <= set(node.leaves)


@pytest.mark.parametrize("n", [32, 80, 100, 200])
def test_counts_cut_gives_groups_when_distances_are_concentrated(n):
    """All distances within [0.8, 1] × the largest, as DTW distances of z-scored windows
    tend to be: fixed fractions of the root height leave levels 1–2 without groups, the
    count cut does not."""
    rng = np.random.default_rng(n)
    d = rng.uniform(0.8, 1.0, size=n * (n - 1) // 2)
    linear = build_tree(d, LINEAR)
    tree = build_tree(d)
    assert tree.bands == "counts"
    assert len(group_candidates(linear)) < n / 8  # the problem the count cut solves
    real = [
        level
        for level in range(1, tree.levels)
        if any(node.kind == "merge" for node in tree.at_level(level))
    ]
    assert len(real) >= 2
    candidates = group_candidates(tree)
    assert len(candidates) >= n / 8
    assert all(2 <= c.size <= 8 for c in candidates)
    # leaf order and ids as with any cut
    assert tree.leaf_order == linear.leaf_order
    assert {node.id for node in tree.nodes() if node.kind == "leaf"} == {f"b{i}" for i in range(n)}


def test_count_thresholds_leave_the_target_numbers_of_clusters():
    n = 81  # k = 3 for 4 levels: 27, 9, 3 clusters, then the root
    heights = np.arange(1.0, n)  # distinct, ascending
    thresholds = count_thresholds(heights, 4)
    for level, clusters in zip((1, 2, 3), (27, 9, 3), strict=True):
        merges_below = int((heights < thresholds[level - 1]).sum())
        assert n - merges_below == clusters
    assert thresholds[-1] == heights[-1]
    assert count_thresholds(np.zeros(0), 3) == (0.0, 0.0, 0.0)


def _dominant_pool(n: int, seed: int, spread: float) -> np.ndarray:
    """Condensed distances of a trained policy's pool: 90 % of the behaviours one cloud of
    radius `spread` (4-D), the rest outliers away from it and from each other."""
    rng = np.random.default_rng(seed)
    main = rng.normal(size=(n - n // 10, 4)) * spread
    outliers = 3.0 + rng.normal(size=(n // 10, 4)) * 2.0
    return pdist(np.concatenate([main, outliers]))


@pytest.mark.parametrize("n", [60, 100, 200, 1000])
@pytest.mark.parametrize("method", ["complete", "average", "ward"])
def test_a_dominant_group_is_split_and_every_level_offers_groups(n, method):
    """Issue 22: the counts cut left one top-level cluster of nearly every behaviour (94 of
    100 in a Hopper session); with the size caps none holds more than half the leaves, and
    levels 1 and 2 each offer selectable (2–8-leaf) groups."""
    d = _dominant_pool(n, seed=n, spread=1.0)
    plain = build_tree(d, TreeConfig(method=method, balance=None))
    tree = build_tree(d, TreeConfig(method=method))
    if method != "ward":  # Ward's merges alone balance this pool, not Hopper's (docs/results)
        assert max(c.size for c in plain.root.children) > n / 2  # the problem
    assert max(c.size for c in tree.root.children) <= n / 2
    for level in (1, 2):
        assert any(2 <= node.size <= 8 for node in tree.at_level(level)), level
    assert all(node.size <= 8 for node in tree.at_level(1))
    check_caps(tree, d, 2.0)
    check_invariants(tree, n)
    assert tree.leaf_order == plain.leaf_order


def test_indistinguishable_behaviours_stay_one_cluster_above_level_1():
    """A cloud whose mean pairwise distance is below half the pool's is not split at levels
    >= 2 (nothing tells its behaviours apart), but level 1 still offers it in groups a
    person can pick."""
    n = 100
    rng = np.random.default_rng(0)
    # 90 near-identical behaviours; ten outliers in pairs, each pair a tight couple
    main = rng.normal(size=(90, 4)) * 1e-3
    couples = np.repeat(rng.normal(size=(5, 4)) * 50.0, 2, axis=0) + rng.normal(size=(10, 4))
    d = pdist(np.concatenate([main, couples]))
    square = squareform(d)
    inner = square[:90, :90].sum() / (90 * 89)
    assert inner <= indistinguishable_spread(d)
    tree = build_tree(d)
    (whole,) = [c for c in tree.root.children if 0 in c.leaves]
    assert set(range(90)) <= set(whole.leaves) and whole.size > n / 2
    assert all(node.size <= 8 for node in tree.at_level(1))
    check_caps(tree, d, 2.0)


def test_level_caps():
    # N = 100, 4 levels: k = 3.16; level 1: MAX_GROUP; 2 k^2 = 20; 2 k^3 = 63 -> N / 2
    # N = 1000: k = 5.62, 2 k^2 = 63.2 -> 64, 2 k^3 = 355.7 -> 356
    assert level_caps(100, 4, 2.0) == (8, 20, 50)
    assert level_caps(1000, 4, 2.0) == (8, 64, 356)
    assert level_caps(10, 4, 2.0) == (5, 5, 5)
    # the top level's own cap (issue 40): 1.25 N / k = 39.5 -> 40 of 100; 222.3 -> 223 of
    # 1,000; never above N / 2 (N = 20: k = 2.11, 2 k^2 = 8.9 -> 9, 11.8 -> 12 > 10), and
    # with 2 levels the top level is level 1, a group's cap
    assert level_caps(100, 4, 2.0, 1.25) == (8, 20, 40)
    assert level_caps(1000, 4, 2.0, 1.25) == (8, 64, 223)
    assert level_caps(1000, 4, 2.0, 4.0) == (8, 64, 356)  # the lower cap wins
    assert level_caps(20, 4, 2.0, 1.25) == (8, 9, 10)
    assert level_caps(100, 2, 2.0, 1.25) == (8,)


def offers_group(node: TreeNode, depth: int = 2) -> bool:
    """At most MAX_GROUP leaves itself, or a node of 2..8 within `depth` levels below."""
    rings, below = [node], []
    for _ in range(depth):
        rings = [c for x in rings for c in x.children]
        below += rings
    return node.size <= 8 or any(2 <= x.size <= 8 for x in below)


@pytest.mark.parametrize(
    ("n", "method", "seed"),
    [(100, "complete", 101), (1000, "complete", 1000), (1000, "average", 1001)],
)
def test_the_top_level_is_balanced_by_its_own_cap(n, method, seed):
    """Issue 40: with the caps of issue 22 alone a top-level cluster may hold up to half the
    pool ([5, 49, 33, 13] of 100); the top level's cap, 1.25 times the mean of the k
    clusters the cut aims for, splits it further, by the dendrogram alone: the leaf order
    and every level below keep their caps, and every top-level cluster offers a group of
    2–8 within two clicks (itself, or focused, a node of its next two rings)."""
    d = _dominant_pool(n, seed=seed, spread=1.0)  # before: 46 of 100, 304 and 355 of 1,000
    before = build_tree(d, TreeConfig(method=method, top_balance=None))
    tree = build_tree(d, TreeConfig(method=method))
    cap = level_caps(n, 4, 2.0, 1.25)[-1]
    assert cap == {100: 40, 1000: 223}[n]
    largest = max(c.size for c in tree.root.children)
    assert largest <= cap < max(c.size for c in before.root.children)  # the cap bit
    check_caps(tree, d, 2.0, 1.25)
    check_invariants(tree, n)
    assert tree.leaf_order == before.leaf_order
    assert all(offers_group(top) for top in tree.root.children)
    assert json.loads(json.dumps(to_json(tree)))["root"]["children"][0].keys() == {
        "id", "kind", "level", "height", "size", "leaves", "children"
    }  # fmt: skip
