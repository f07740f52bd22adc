"""The scalable group-variance score and suggestion order (issue 22) give what the first
implementation gave: a copy of it (commit 66f54ea, `query/groups.py`) is kept here as the
reference and both run on the same seeded pools of 200 behaviours."""

import numpy as np
import pytest
from scipy.spatial.distance import pdist

from groupwise.behaviour import TreeConfig, build_tree, group_candidates
from groupwise.query.groups import (
    INTRA_FLOOR,
    GroupCandidate,
    group_inter,
    pair_variance_matrix,
    score_group_pairs,
    suggestion_order,
)

# -- the reference: the implementation before issue 22, verbatim but for names -------------


def _ref_membership(candidates, n):
    m = np.zeros((len(candidates), n))
    for g, c in enumerate(candidates):
        m[g, np.asarray(c.members)] = 1.0 / len(c.members)
    return m


def _ref_normalised(x, floor, if_zero):
    top = x.max() if x.size else 0.0
    if not top > 0:
        return np.full_like(x, if_zero)
    return np.maximum(x / top, floor)


def _ref_scores(returns, intra, candidates):
    r = np.asarray(returns, dtype=np.float64)
    v = np.asarray(intra, dtype=np.float64)
    membership = _ref_membership(candidates, r.shape[0])
    inter_all = membership @ pair_variance_matrix(r) @ membership.T
    intra_group = membership @ v
    overlap = (membership > 0).astype(np.int64) @ (membership > 0).T.astype(np.int64)
    i, j = np.triu_indices(len(candidates), k=1)
    disjoint = overlap[i, j] == 0
    i, j = i[disjoint], j[disjoint]
    sizes = np.array([len(c.members) for c in candidates], dtype=np.float64)
    inter = inter_all[i, j]
    intra_pair = np.maximum(intra_group[i], intra_group[j])
    penalty = 1.0 + np.abs(sizes[i] - sizes[j]) / (sizes[i] + sizes[j])
    score = _ref_normalised(inter, 0.0, 0.0) / _ref_normalised(intra_pair, INTRA_FLOOR, 1.0)
    return np.stack([i, j], axis=1), inter, intra_pair, penalty, score / penalty


def _ref_order(pairs, score, count, max_uses=2, refill=False):
    order = np.argsort(-score, kind="stable")
    taken = np.zeros(len(score), dtype=bool)
    chosen = []
    while len(chosen) < count:
        uses = {}
        before = len(chosen)
        for row in order:
            if len(chosen) >= count:
                break
            if taken[row]:
                continue
            a, b = (int(x) for x in pairs[row])
            if uses.get(a, 0) >= max_uses or uses.get(b, 0) >= max_uses:
                continue
            uses[a] = uses.get(a, 0) + 1
            uses[b] = uses.get(b, 0) + 1
            taken[row] = True
            chosen.append(int(row))
        if not refill or len(chosen) == before:
            break
    return chosen


# -- the comparison ------------------------------------------------------------------------


def _pool(n, seed, tree_cfg):
    """A clustered pool's tree candidates (levels 1 and 2, and 1-3 for more of them) and
    ensemble returns (N, 3) with member disagreement of varying size."""
    rng = np.random.default_rng(seed)
    centres = rng.normal(size=(10, 4)) * 3
    points = centres[rng.integers(0, 10, n)] + rng.normal(size=(n, 4))
    tree = build_tree(pdist(points), tree_cfg)
    nodes = group_candidates(tree, levels=(1, 2, 3))
    candidates = [GroupCandidate(c.id, c.leaves) for c in nodes]
    returns = rng.normal(size=(n, 1)) * 20 + rng.normal(size=(n, 3)) * rng.gamma(2, 1, (n, 1))
    intra = rng.gamma(2.0, 0.5, size=n)
    return returns, intra, candidates


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("method", ["complete", "ward"])
def test_scores_and_suggestions_equal_the_first_implementation_at_200(seed, method):
    returns, intra, candidates = _pool(200, seed, TreeConfig(method=method))
    assert len(candidates) > 20
    got = score_group_pairs(returns, intra, candidates)
    pairs, inter, intra_pair, penalty, score = _ref_scores(returns, intra, candidates)
    np.testing.assert_array_equal(got.pairs, pairs)
    np.testing.assert_allclose(got.inter, inter, rtol=1e-10)
    np.testing.assert_array_equal(got.intra, intra_pair)
    np.testing.assert_array_equal(got.size_penalty, penalty)
    np.testing.assert_allclose(got.score, score, rtol=1e-10)
    # the order the reference gives on its own scores, for short and long lists, with and
    # without refilling, one or two uses per candidate
    for count in (1, 10, 50, len(pairs) // 3, len(pairs) + 5):
        for max_uses in (1, 2):
            for refill in (False, True):
                expected = _ref_order(pairs, score, count, max_uses, refill)
                rows = suggestion_order(got, count, max_uses, refill).tolist()
                assert rows == expected, (count, max_uses, refill)


def test_group_inter_equals_the_mean_of_pair_variances():
    rng = np.random.default_rng(3)
    returns = rng.normal(size=(30, 4)) * 5 + 100
    membership = rng.random((6, 30)) * (rng.random((6, 30)) < 0.3)
    membership /= membership.sum(axis=1, keepdims=True)
    expected = membership @ pair_variance_matrix(returns) @ membership.T
    np.testing.assert_allclose(group_inter(returns, membership), expected, rtol=1e-9)
