"""From one group judgement to preference pairs (SPEC §6)."""

import math
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


Derivation = Callable[[Judgement, np.random.Generator], list[Pair]]
"""A judgement and a generator → its preference pairs."""


def oversample_pairs(
    judgement: Judgement, derive: Derivation, factor: float, rng: np.random.Generator
) -> list[Pair]:
    """⌊factor × k + ½⌋ pairs of `judgement`, where k is the number `derive` gives.

    The first k are `derive`'s; the rest come from further calls of `derive` (each shuffled
    afresh by `rng`: another covering draw, or the same m × n pairs again), cut at the count.
    A judgement of two single behaviours gives its one pair `factor` times over. With
    factor 1 this is exactly `derive(judgement, rng)`, drawing the same numbers from `rng`.

    Raises:
        ValueError: `factor` below 1.
    """
    if factor < 1:
        raise ValueError(f"pair oversampling factor must be >= 1, got {factor}")
    pairs = derive(judgement, rng)
    want = math.floor(factor * len(pairs) + 0.5)
    while len(pairs) < want:
        pairs += derive(judgement, rng)
    return pairs[:want]


PAIR_DERIVATIONS: dict[str, Derivation] = {
    "cover": covering_pairs,
    "cartesian": cartesian_pairs,
}


PAIR_STREAM = 1
"""The key that sets the pair streams apart from a run's round streams."""


def pair_rng(seed: int, round_index: int, key: int) -> np.random.Generator:
    """The generator of the pairs of judgement number `key` of a round (0, 1, … in the order
    the judgements were given, undone ones included)."""
    return np.random.default_rng(np.random.SeedSequence([seed, round_index, PAIR_STREAM, key]))


def judgement_pairs(
    judgement: Judgement,
    derivation: str,
    oversample: float,
    *,
    seed: int,
    round_index: int,
    key: int,
) -> list[Pair]:
    """The preference pairs of judgement `key` of a round: `derivation` ("cover" or
    "cartesian", SPEC §6) times `oversample` (`oversample_pairs`), drawn from its own stream
    (`pair_rng`). The one derivation: the app calls it when a judgement arrives, the round's
    end (`groupwise.run.round.end_round`) for every judgement of the round.

    Raises:
        KeyError: unknown derivation.
    """
    derive = PAIR_DERIVATIONS[derivation]
    return oversample_pairs(judgement, derive, oversample, pair_rng(seed, round_index, key))
