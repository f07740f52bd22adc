"""From one group judgement to preference pairs (SPEC §6)."""

from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from groupwise.preferences.judgement import Judgement


class Pair(NamedTuple):
    """Two pool indices and the probability that `a` is preferred (1.0, 0.5 or 0.0)."""

    a: int
    b: int
    label: float


def covering_pairs(judgement: Judgement, rng: np.random.Generator) -> list[Pair]:
    """max(m, n) pairs in which every member of both groups appears at least once.

    Both groups are shuffled with `rng`, the smaller one is cycled, and the two are zipped.
    """
    left = rng.permutation(np.asarray(judgement.left))
    right = rng.permutation(np.asarray(judgement.right))
    n = max(len(left), len(right))
    return [
        Pair(int(left[i % len(left)]), int(right[i % len(right)]), judgement.label)
        for i in range(n)
    ]


def cartesian_pairs(judgement: Judgement, rng: np.random.Generator) -> list[Pair]:
    """All m × n pairs (the earlier CLRVis method), kept for ablations; `rng` is unused."""
    del rng
    return [Pair(a, b, judgement.label) for a in judgement.left for b in judgement.right]


def cap_pairs(pairs: list[Pair], limit: int, rng: np.random.Generator) -> list[Pair]:
    """At most `limit` of `pairs`, drawn without replacement, in their original order."""
    if limit < 0:
        raise ValueError(f"pair limit must be >= 0, got {limit}")
    if len(pairs) <= limit:
        return list(pairs)
    keep = np.sort(rng.choice(len(pairs), size=limit, replace=False))
    return [pairs[i] for i in keep]


PAIR_DERIVATIONS: dict[str, Callable[[Judgement, np.random.Generator], list[Pair]]] = {
    "cover": covering_pairs,
    "cartesian": cartesian_pairs,
}
