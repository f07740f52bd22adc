"""The one feedback interface that a person and a simulated decision-maker both implement."""

from typing import Protocol

import numpy as np

from groupwise.pool import BehaviourPool
from groupwise.preferences.judgement import Judgement


class Oracle(Protocol):
    """Gives up to `n_queries` comparisons on a pool.

    A skipped comparison uses up its query and yields no judgement, so the list may be
    shorter than `n_queries`.
    """

    def gather(self, pool: BehaviourPool, n_queries: int, rng: np.random.Generator) -> list[Judgement]: ...
