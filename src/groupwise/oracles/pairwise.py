"""Pairwise-DM (SPEC §7): the standard RLHF baseline, one pair per query."""

from dataclasses import dataclass

import numpy as np

from groupwise.oracles.noise import perceived_returns, preference
from groupwise.pool import BehaviourPool
from groupwise.preferences.judgement import Judgement, Source
from groupwise.query.pairwise import select_pairs


@dataclass(frozen=True)
class PairwiseDM:
    """Asks the pairs chosen by pairwise active learning and labels them by noisy true return.

    For each query the most disputed of `candidates` random pairs is asked (ensemble
    variance of the return difference); both returns are perceived with fresh noise.
    """

    sigma: float = 0.25
    candidates: int = 10
    beta: float | None = None

    def gather(self, pool: BehaviourPool, n_queries: int, rng: np.random.Generator) -> list[Judgement]:
        if n_queries <= 0 or len(pool) < 2:
            return []
        pairs = select_pairs(pool.predicted_returns, n_queries, self.candidates, rng)
        true = pool.true_returns
        length = pool.fragments[0].length
        judgements = []
        for a, b in pairs:
            seen_a, seen_b = perceived_returns(true[[a, b]], length, self.sigma, rng)
            label = preference(seen_a, seen_b, rng, self.beta)
            judgements.append(Judgement((int(a),), (int(b),), label, Source.SIMULATED))
        return judgements
