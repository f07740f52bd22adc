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
"""

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

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


def score_group_pairs(
    returns: FloatArray, intra: FloatArray, candidates: Sequence[GroupCandidate]
) -> GroupPairScores:
    """The group-variance score (module docstring) of every disjoint pair of candidates.

    returns: (N, K) predicted returns; intra: (N,) per-behaviour intra variance
    (`step_variance` or `return_variance`); candidates: G groups of pool indices.
    Pairs sharing a behaviour are not scored. O(N² K + G² N).
    """
    r = np.asarray(returns, dtype=np.float64)
    v = np.asarray(intra, dtype=np.float64)
    n = r.shape[0]
    if r.ndim != 2 or v.shape != (n,):
        raise ValueError(f"expected returns (N, K) and intra (N,), got {r.shape} and {v.shape}")
    if len(candidates) < 2:
        empty = np.zeros(0)
        return GroupPairScores(np.zeros((0, 2), dtype=np.int64), empty, empty, empty, empty)
    membership = _membership(candidates, n)
    inter_all = membership @ pair_variance_matrix(r) @ membership.T  # (G, G)
    intra_group = membership @ v  # (G,)
    overlap = (membership > 0).astype(np.int64) @ (membership > 0).T.astype(np.int64)
    i, j = np.triu_indices(len(candidates), k=1)
    disjoint = overlap[i, j] == 0
    i, j = i[disjoint], j[disjoint]
    sizes = np.array([len(c.members) for c in candidates], dtype=np.float64)
    inter = inter_all[i, j]
    intra_pair = np.maximum(intra_group[i], intra_group[j])
    penalty = 1.0 + np.abs(sizes[i] - sizes[j]) / (sizes[i] + sizes[j])
    score = _normalised(inter, floor=0.0, if_zero=0.0) / _normalised(
        intra_pair, floor=INTRA_FLOOR, if_zero=1.0
    )
    return GroupPairScores(
        pairs=np.stack([i, j], axis=1).astype(np.int64),
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
    scores: GroupPairScores, count: int, max_uses: int = 2, refill: bool = False
) -> IntArray:
    """Rows of `scores` to suggest, best first, at most `count` of them.

    Pairs are taken by descending score (ties keep the lower row), skipping a pair when
    either candidate already appears in `max_uses` taken pairs (SPEC §5: each node in at
    most 2 suggestions). With `refill`, once that list is used up a new list is built the
    same way over the pairs not yet taken (use counts start again), as a user who keeps
    asking for suggestions would get, until `count` pairs or every pair is taken.
    """
    if max_uses < 1:
        raise ValueError(f"max uses must be >= 1, got {max_uses}")
    order = np.argsort(-scores.score, kind="stable")
    taken = np.zeros(len(scores), dtype=bool)
    chosen: list[int] = []
    while len(chosen) < count:
        uses: dict[int, int] = {}
        before = len(chosen)
        for row in order:
            if len(chosen) >= count:
                break
            if taken[row]:
                continue
            a, b = (int(x) for x in scores.pairs[row])
            if uses.get(a, 0) >= max_uses or uses.get(b, 0) >= max_uses:
                continue
            uses[a] = uses.get(a, 0) + 1
            uses[b] = uses.get(b, 0) + 1
            taken[row] = True
            chosen.append(int(row))
        if not refill or len(chosen) == before:
            break
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
