"""A round's judgements → its preference pairs (SPEC §3): each judgement's pairs from its own
stream, keyed by its place in the round (`preferences.pairs.judgement_pairs`), then the
round's pair cap. `end_round` and a continuous round's refits (`run.continuous`) derive them
alike, so a judgement gives the same pairs wherever it is counted."""

import math
from collections.abc import Sequence

import numpy as np

from groupwise.config import LoopConfig
from groupwise.preferences.judgement import Judgement
from groupwise.preferences.pairs import Pair, cap_pairs, judgement_pairs


def derive_pairs(
    judgements: Sequence[Judgement],
    loop: LoopConfig,
    round_index: int,
    keys: Sequence[int] | None = None,
) -> list[Pair]:
    """Each judgement's preference pairs (`preferences.pairs.judgement_pairs`, by
    `loop.pair_derivation` × `loop.pair_oversample`), keyed by `keys`: by default its place
    in the list."""
    keys = range(len(judgements)) if keys is None else keys
    if len(keys) != len(judgements):
        raise ValueError(f"{len(keys)} keys for {len(judgements)} judgements")
    return [
        pair
        for judgement, key in zip(judgements, keys, strict=True)
        for pair in judgement_pairs(
            judgement,
            loop.pair_derivation,
            loop.pair_oversample,
            seed=loop.seed,
            round_index=round_index,
            key=key,
        )
    ]


def round_pairs(
    judgements: Sequence[Judgement],
    loop: LoopConfig,
    round_index: int,
    budget: int,
    rng: np.random.Generator,
    keys: Sequence[int] | None = None,
) -> list[Pair]:
    """The round's preference pairs (`derive_pairs`), then at most ⌊pair_cap × budget⌋ of
    them when `loop.pair_cap` is set (the budget of a round without one: its judgements),
    drawn from `rng`."""
    pairs = derive_pairs(judgements, loop, round_index, keys)
    if loop.pair_cap is None:
        return pairs
    return cap_pairs(pairs, math.floor(loop.pair_cap * (budget or len(judgements))), rng)
