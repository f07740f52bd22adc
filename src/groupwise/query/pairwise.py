"""Pairwise active learning (SPEC §5): disagreement of the ensemble about a pair."""

import numpy as np

from groupwise.types import FloatArray, IntArray


def pair_scores(returns: FloatArray, pairs: IntArray) -> FloatArray:
    """Var_k[R_k(a) − R_k(b)] for each pair.

    returns: (N, K) predicted return of each behaviour per ensemble member.
    pairs: (P, 2) behaviour indices. Returns (P,).
    """
    diff = returns[pairs[:, 0]] - returns[pairs[:, 1]]
    return diff.var(axis=1)


def random_pairs(n: int, count: int, rng: np.random.Generator) -> IntArray:
    """(count, 2) uniformly random pairs of distinct indices below `n`."""
    if n < 2:
        raise ValueError(f"a pair needs at least 2 behaviours, the pool has {n}")
    a = rng.integers(0, n, size=count)
    b = (a + rng.integers(1, n, size=count)) % n
    return np.stack([a, b], axis=1)


def select_pairs(
    returns: FloatArray, n_queries: int, n_candidates: int, rng: np.random.Generator
) -> IntArray:
    """(n_queries, 2): for each query, the most disputed of `n_candidates` random pairs."""
    candidates = random_pairs(len(returns), n_queries * n_candidates, rng)
    scores = pair_scores(returns, candidates).reshape(n_queries, n_candidates)
    best = scores.argmax(axis=1)
    return candidates.reshape(n_queries, n_candidates, 2)[np.arange(n_queries), best]


def top_pairs(returns: FloatArray, k: int) -> tuple[IntArray, FloatArray]:
    """The k highest-scoring pairs over all N(N−1)/2 pairs, best first, with their scores."""
    a, b = np.triu_indices(len(returns), k=1)
    pairs = np.stack([a, b], axis=1)
    scores = pair_scores(returns, pairs)
    k = min(k, len(scores))
    best = np.argpartition(-scores, k - 1)[:k] if k > 0 else np.zeros(0, dtype=int)
    best = best[np.argsort(-scores[best], kind="stable")]
    return pairs[best], scores[best]
