"""How much a round's pool holds of a target's behaviour: each behaviour's mean per-step target
score, recorded for every pool a case study's query strategy is asked about."""

import numpy as np

from groupwise.behaviour.pool import BehaviourPool
from groupwise.query.strategies import Query, QueryStrategy
from groupwise.types import FloatArray


def pool_scores(pool: BehaviourPool) -> np.ndarray:
    """Each behaviour's mean per-step target score (N,): its true return over its length."""
    lengths = np.array([f.length for f in pool.fragments], dtype=float)
    return np.asarray(pool.true_returns, dtype=float) / lengths


class PoolRecorder:
    """A query strategy that scores every pool it is asked about (`pool_scores`, kept per
    round: a continuous run asks about round r + 1's pool before round r ends) and lets the
    run's own strategy answer."""

    def __init__(self, inner: QueryStrategy) -> None:
        self.inner = inner
        self.scores: dict[int, FloatArray] = {}

    def propose(self, pool: BehaviourPool, n_queries: int, rng: np.random.Generator) -> list[Query]:
        self.scores[pool.round] = pool_scores(pool)
        return self.inner.propose(pool, n_queries, rng)

    def __getattr__(self, name: str) -> object:  # the strategy's `candidates`, if it has them
        return getattr(self.inner, name)
