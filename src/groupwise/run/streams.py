"""A run's random streams: everything random in a round comes from (seed, round) alone.

Each round draws from `SeedSequence([seed, round])` spawned per phase (`RoundStreams`), so a
round's result depends only on the checkpointed state before it and a resumed run repeats an
uninterrupted one exactly. A judgement's preference pairs have a stream of their own,
keyed by its place in the round (`groupwise.preferences.pairs.pair_rng`), so the app can
derive them when the judgement arrives and the round's end derives the same ones again.
"""

from typing import NamedTuple

import numpy as np


def init_rng(seed: int) -> np.random.Generator:
    """The generator of the reward ensemble's initial weights."""
    return np.random.default_rng(np.random.SeedSequence([seed, 2**20]))


def eval_rng(seed: int) -> np.random.Generator:
    """The evaluation's generator: the same reset seeds after every round."""
    return np.random.default_rng(np.random.SeedSequence([seed, 2**21]))


class RoundStreams(NamedTuple):
    """A round's independent random streams, one per phase (the app runs them apart)."""

    sample: np.random.Generator
    """Sampling the pool from the policy."""
    feedback: np.random.Generator
    """The strategy's queries, then the (simulated) teacher's answers."""
    pairs: np.random.Generator
    """Capping the round's pairs (`LoopConfig.pair_cap`)."""
    fit: np.random.Generator
    """Fitting the reward ensemble."""
    ppo: np.random.Generator
    """The PPO seed of the round."""


def round_streams(seed: int, round_index: int) -> RoundStreams:
    """Round `round_index`'s streams, independent of how earlier rounds were run."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, round_index]))
    return RoundStreams(*rng.spawn(5))


def pretrain_rng(seed: int) -> np.random.Generator:
    """The generator of the pre-training before round 0 (`groupwise.run.pretrain`)."""
    return np.random.default_rng(np.random.SeedSequence([seed, 2**23]))


def takeaway_streams(seed: int) -> tuple[np.random.SeedSequence, np.random.Generator]:
    """The take-away choice's streams (`groupwise.run.takeaway`): the seed of every round's
    episodes (each round's generator starts from it, so all rounds play the same reset
    seeds) and the teacher's generator."""
    episodes, teacher = np.random.SeedSequence([seed, 2**22]).spawn(2)
    return episodes, np.random.default_rng(teacher)
