"""The Pairwise-DM's teacher (SPEC §7): labels a pair by noisy true return."""

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from groupwise.behaviour.pool import BehaviourPool
from groupwise.preferences.judgement import Judgement, Source
from groupwise.query.strategies import Query
from groupwise.teachers.noise import perceived_returns, preference


@dataclass(frozen=True)
class PairwiseTeacher:
    """Answers pairs (groups of one): both returns perceived with fresh noise, the higher
    wins (0.5 on an exact tie), or with `beta` a Boltzmann-rational choice
    P(a) = σ((R(a) − R(b)) / β), as the paper's reference code labels.

    It answers pairs only; `SimulatedTeacher` answers groups.
    """

    sigma: float = 0.25
    beta: float | None = None

    def answer(
        self, pool: BehaviourPool, queries: Sequence[Query], rng: np.random.Generator
    ) -> list[Judgement]:
        true = pool.true_returns
        judgements = []
        for query in queries:
            if len(query.left) != 1 or len(query.right) != 1:
                raise ValueError(f"the pairwise teacher answers pairs only, got {query}")
            (a,), (b,) = query.left, query.right
            length = pool.fragments[a].length
            seen_a, seen_b = perceived_returns(true[[a, b]], length, self.sigma, rng)
            label = preference(seen_a, seen_b, rng, self.beta)
            judgements.append(Judgement((a,), (b,), label, Source.SIMULATED))
        return judgements
