"""Group active learning (SPEC §5): the group-variance score and the suggestion list.

For candidate groups A, B (disjoint, sizes m and n) of a pool with predicted returns
R_k(f) (N, K):

    inter(A, B) = mean over a ∈ A, b ∈ B of Var_k[R_k(a) − R_k(b)]
    intra(G)    = mean over f ∈ G of intra(f)
    intra(A, B) = max(intra(A), intra(B))
    score       = (inter / max inter) / (intra / max intra) / (1 + |m − n| / (m + n))

with both maxima taken over all scored candidate pairs.

intra(f), "the variance of f's per-step member rewards", is read as the ensemble's
disagreement about f's steps: with r_k(f, t) member k's reward for step t,

    intra(f) = mean over t of Var_k[r_k(f, t)]          (`step_variance`)

This is the reading that matches the paper's rationale ("lower if [the predictors] are less
certain about the quality of the behaviours within the groups"). The other literal reading,
the variance over all K·L values together, equals this plus Var_t[mean_k r_k(f, t)] (law of
total variance): it would add how much the reward changes *along* the fragment, which says
nothing about the ensemble's certainty and would penalise every fragment with a dynamic
reward. When the per-step rewards are unavailable, `return_variance` gives
Var_k[R_k(f)] / L, which equals `step_variance` when the members' per-step deviations are
uncorrelated across steps; the score only uses intra / max intra, so the 1/L cancels.

Zero guards (no NaN or inf): when max inter is 0 every normalised inter is 0 (all scores 0);
when max intra is 0 every normalised intra is 1 (intra carries no information); a
normalised intra below `INTRA_FLOOR` is raised to it, so a perfectly certain group scores
high but finitely.

Variances are population variances over members (ddof 0), as in `pair_scores`.

The suggestions are taken in the order of this score (SPEC §5).
"""

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import sparse

from groupwise.types import FloatArray, IntArray

INTRA_FLOOR = 1e-6
"""Smallest normalised intra term: keeps the score finite for a group the ensemble is sure of."""


@dataclass(frozen=True)
class GroupCandidate:
    """A group the interface can offer: a tree node id and its behaviours (pool indices)."""

    id: str
    members: tuple[int, ...]

    def __post_init__(self) -> None:
        if not self.members:
            raise ValueError(f"candidate {self.id} has no members")
        if len(set(self.members)) != len(self.members):
            raise ValueError(f"candidate {self.id} lists a behaviour twice")


@dataclass(frozen=True)
class GroupPairScores:
    """Every disjoint pair of candidates with the parts of its group-variance score.

    `pairs` rows index the candidate list, first index lower; the other arrays are (P,).
    """

    pairs: IntArray  # (P, 2)
    inter: FloatArray  # (P,) mean pair variance between the groups
    intra: FloatArray  # (P,) max of the two groups' mean intra variance
    size_penalty: FloatArray  # (P,) 1 + |m − n| / (m + n)
    score: FloatArray  # (P,)

    def __len__(self) -> int:
        return int(self.pairs.shape[0])


@dataclass(frozen=True)
class GroupSuggestion:
    """One suggested comparison: two disjoint candidates and their score."""

    left: GroupCandidate
    right: GroupCandidate
    score: float


def pair_variance_matrix(returns: FloatArray) -> FloatArray:
    """(N, N) Var_k[R_k(a) − R_k(b)] for every pair; returns (N, K). Zero diagonal."""
    r = np.asarray(returns, dtype=np.float64)
    centred = r - r.mean(axis=1, keepdims=True)
    diff = centred[:, None, :] - centred[None, :, :]
    return np.asarray((diff**2).mean(axis=2))


def step_variance(step_rewards: FloatArray) -> FloatArray:
    """(N,) intra(f) = mean over steps of the variance over members of the step reward.

    step_rewards: (K, N, L) member k's reward for step t of behaviour f, as
    `RewardEnsemble.step_rewards(obs, acts)` returns for obs (N, L, obs_dim).
    """
    r = np.asarray(step_rewards, dtype=np.float64)
    if r.ndim != 3:
        raise ValueError(f"expected per-step rewards (K, N, L), got {r.shape}")
    return np.asarray(r.var(axis=0).mean(axis=1))


def return_variance(returns: FloatArray, length: int) -> FloatArray:
    """(N,) Var_k[R_k(f)] / L: the stand-in for `step_variance` from returns (N, K) alone."""
    if length < 1:
        raise ValueError(f"fragment length must be >= 1, got {length}")
    return np.asarray(np.asarray(returns, dtype=np.float64).var(axis=1) / length)


def _membership(candidates: Sequence[GroupCandidate], n: int) -> FloatArray:
    """(G, N) row g has 1 / |g| on the members of candidate g, so M @ x averages x per group."""
    m = np.zeros((len(candidates), n))
    for g, c in enumerate(candidates):
        idx = np.asarray(c.members)
        if idx.min() < 0 or idx.max() >= n:
            raise ValueError(f"candidate {c.id} has a behaviour outside the pool of {n}")
        m[g, idx] = 1.0 / len(idx)
    return m


def group_inter(returns: FloatArray, membership: FloatArray) -> FloatArray:
    """(G, G) inter(A, B) = mean over a ∈ A, b ∈ B of Var_k[R_k(a) − R_k(b)].

    With c_f = R(f) − mean_k R_k(f) (centred over members), Var_k[R_k(a) − R_k(b)] =
    (|c_a|² + |c_b|² − 2 c_a·c_b) / K, so the group means need only the (G, K) group means of
    c and the (G,) group means of |c|² / K: O(G N K + G² K), where building the (N, N)
    `pair_variance_matrix` first cost O(N² K) time and memory (issue 22: 0.3–0.5 s and
    24 MB at N = 1,000). Equal to `membership @ pair_variance_matrix(returns) @
    membership.T` up to rounding.
    """
    r = np.asarray(returns, dtype=np.float64)
    k = r.shape[1]
    centred = r - r.mean(axis=1, keepdims=True)
    own = membership @ ((centred**2).sum(axis=1) / k)  # (G,)
    mean_c = membership @ centred  # (G, K)
    inter = own[:, None] + own[None, :] - (2.0 / k) * (mean_c @ mean_c.T)
    return np.asarray(np.maximum(inter, 0.0))


def _disjoint_pairs(candidates: Sequence[GroupCandidate], n: int) -> IntArray:
    """(P, 2) rows i < j of the candidates that share no behaviour, in row-major order.

    The overlaps are a sparse product of the (G, N) incidence matrix with itself: its cost
    grows with the candidates that share behaviours, not with G² N.
    """
    g = len(candidates)
    rows = np.concatenate([np.full(len(c.members), k) for k, c in enumerate(candidates)])
    cols = np.concatenate([np.asarray(c.members) for c in candidates])
    member = sparse.csr_array((np.ones(rows.size), (rows, cols)), shape=(g, n))
    overlap = (member @ member.T).tocoo()
    shared = np.zeros((g, g), dtype=bool)
    shared[overlap.row, overlap.col] = True
    i, j = np.triu_indices(g, k=1)
    keep = ~shared[i, j]
    return np.stack([i[keep], j[keep]], axis=1).astype(np.int64)


def score_group_pairs(
    returns: FloatArray, intra: FloatArray, candidates: Sequence[GroupCandidate]
) -> GroupPairScores:
    """The group-variance score (module docstring) of every disjoint pair of candidates.

    returns: (N, K) predicted returns; intra: (N,) per-behaviour intra variance
    (`step_variance` or `return_variance`); candidates: G groups of pool indices.
    Pairs sharing a behaviour are not scored. O(G N (K + G) + G² K) (`group_inter`): at
    1,000 behaviours the G ≈ 100–300 tree candidates are scored in milliseconds
    (`benchmarks/suggestions.py`).
    """
    r = np.asarray(returns, dtype=np.float64)
    v = np.asarray(intra, dtype=np.float64)
    n = r.shape[0]
    if r.ndim != 2 or v.shape != (n,):
        raise ValueError(f"expected returns (N, K) and intra (N,), got {r.shape} and {v.shape}")
    if len(candidates) < 2:
        empty = np.zeros(0)
        return GroupPairScores(np.zeros((0, 2), dtype=np.int64), *(empty,) * 4)
    membership = _membership(candidates, n)
    pairs = _disjoint_pairs(candidates, n)
    i, j = pairs[:, 0], pairs[:, 1]
    inter = group_inter(r, membership)[i, j]
    intra_group = membership @ v  # (G,)
    sizes = np.array([len(c.members) for c in candidates], dtype=np.float64)
    intra_pair = np.maximum(intra_group[i], intra_group[j])
    penalty = 1.0 + np.abs(sizes[i] - sizes[j]) / (sizes[i] + sizes[j])
    score = _normalised(inter, floor=0.0, if_zero=0.0) / _normalised(
        intra_pair, floor=INTRA_FLOOR, if_zero=1.0
    )
    return GroupPairScores(
        pairs=pairs,
        inter=inter,
        intra=intra_pair,
        size_penalty=penalty,
        score=score / penalty,
    )


def _normalised(x: FloatArray, floor: float, if_zero: float) -> FloatArray:
    """x / max x, at least `floor`; all `if_zero` when the maximum is not positive."""
    top = x.max() if x.size else 0.0
    if not top > 0:
        return np.full_like(x, if_zero)
    return np.maximum(x / top, floor)


def suggestion_order(
    scores: GroupPairScores,
    count: int,
    max_uses: int = 2,
    refill: bool = False,
) -> IntArray:
    """Rows of `scores` to suggest, best first, at most `count` of them.

    Pairs are taken by descending score; ties keep the lower row. A pair is skipped when
    either candidate already appears in `max_uses` taken pairs (SPEC §5: each node in at
    most 2 suggestions). With `refill`, once that list is used up a new list is built the
    same way over the pairs not yet taken (use counts start again), as a user who keeps
    asking for suggestions would get, until `count` pairs or every pair is taken.
    """
    if max_uses < 1:
        raise ValueError(f"max uses must be >= 1, got {max_uses}")
    order = np.argsort(-scores.score, kind="stable")
    chosen: list[int] = []
    if len(scores) == 0 or count <= 0:
        return np.asarray(chosen, dtype=np.int64)
    g = int(scores.pairs.max()) + 1
    while len(chosen) < count and order.size:
        # one list: the best remaining pair whose candidates both have uses left is taken;
        # the pairs before it can no longer be (uses only grow), so the scan resumes after
        # it. Each step is one vectorised pass over the rest: O(taken · P) numpy work
        # instead of a Python loop over every pair of every list (issue 22).
        uses = np.zeros(g, dtype=np.int64)
        a, b = scores.pairs[order, 0], scores.pairs[order, 1]
        taken = np.zeros(order.size, dtype=bool)
        start = 0
        while len(chosen) < count and start < order.size:
            free = (uses[a[start:]] < max_uses) & (uses[b[start:]] < max_uses)
            hit = int(np.argmax(free))
            if not free[hit]:
                break
            pos = start + hit
            taken[pos] = True
            chosen.append(int(order[pos]))
            uses[a[pos]] += 1
            uses[b[pos]] += 1
            start = pos + 1
        if not refill or not taken.any():
            break
        order = order[~taken]
    return np.asarray(chosen, dtype=np.int64)


def suggest_groups(
    returns: FloatArray,
    intra: FloatArray,
    candidates: Sequence[GroupCandidate],
    count: int,
    max_uses: int = 2,
    refill: bool = False,
) -> list[GroupSuggestion]:
    """Up to `count` suggested comparisons, best first (`score_group_pairs`, then
    `suggestion_order`). The left group is the one listed first among the candidates."""
    scores = score_group_pairs(returns, intra, candidates)
    rows = suggestion_order(scores, count, max_uses, refill)
    return [
        GroupSuggestion(
            left=candidates[int(scores.pairs[row, 0])],
            right=candidates[int(scores.pairs[row, 1])],
            score=float(scores.score[row]),
        )
        for row in rows
    ]
