"""A simulated teacher as good as the paper's people (issue 20).

SPEC §7's decision-maker perceives each behaviour with noise of a fixed size per step
(σ = 0.25 in the env's reward units). On a pool whose returns barely differ that teacher is
near coin flips: the case studies' round-0 label error was 0.34–0.46. The paper's user study
measured what people do instead: 10.8 % of preferences wrong with the groupwise interface,
12.8 % pairwise ("The User Study", results).

`CalibratedTeacher` sets its perception noise per pool, relative to what it compares: the
per-behaviour noise sd s at which a comparison of two behaviours of unequal true return is
wrong with probability `label_error` on average over the pool's pairs,

    mean over untied pairs (i, j) of Φ(−|R_i − R_j| / (√2 · s)) = label_error,

then answers as the wrapped teacher would with σ = s / L. Any strategy's queries can be
answered this way, and every teacher of `groupwise.teachers` (group decision, pairwise,
B-Pref imperfections) keeps its own decision rule.
"""

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.special import ndtr

from groupwise.behaviour.pool import BehaviourPool
from groupwise.preferences.judgement import Judgement
from groupwise.query.strategies import Query
from groupwise.teachers.base import Teacher
from groupwise.types import FloatArray

PEOPLE_LABEL_ERROR = 0.12
"""About the paper's people: 10.8 % (groupwise interface) to 12.8 % (pairwise) wrong."""
MAX_PAIRS = 200_000
"""Pairs the calibration averages over (evenly spaced among all of a larger pool's)."""


def pair_error(true_returns: FloatArray, noise_sd: float) -> float:
    """The expected share of wrong labels on the untied pairs of `true_returns` when each
    behaviour is perceived with Normal(0, noise_sd²) noise (nan without untied pairs)."""
    gaps = _untied_gaps(np.asarray(true_returns, dtype=np.float64))
    if gaps.size == 0:
        return math.nan
    if noise_sd <= 0:
        return 0.0
    return float(ndtr(-gaps / (math.sqrt(2.0) * noise_sd)).mean())


def calibrated_noise_sd(true_returns: FloatArray, label_error: float) -> float:
    """The per-behaviour noise sd at which `pair_error` is `label_error` (module docstring);
    0 for a pool without untied pairs (nothing to get wrong).

    Raises:
        ValueError: `label_error` not in (0, 0.5).
    """
    if not 0.0 < label_error < 0.5:
        raise ValueError(f"a label error must be in (0, 0.5), got {label_error}")
    gaps = _untied_gaps(np.asarray(true_returns, dtype=np.float64))
    if gaps.size == 0:
        return 0.0
    low, high = math.log(gaps.min()) - 10.0, math.log(gaps.max()) + 10.0
    scaled = gaps / math.sqrt(2.0)
    for _ in range(80):  # bisection on log s: the error grows with s, from 0 to ½
        middle = (low + high) / 2.0
        if ndtr(-scaled / math.exp(middle)).mean() < label_error:
            low = middle
        else:
            high = middle
    return math.exp((low + high) / 2.0)


@dataclass(frozen=True)
class CalibratedTeacher:
    """A teacher whose noise is set per pool so that its label error on untied behaviour
    pairs is `label_error` (module docstring). `make(sigma)` builds the wrapped teacher with
    per-step noise σ (e.g. `lambda sigma: SimulatedTeacher(Perception(sigma))`)."""

    make: Callable[[float], Teacher]
    label_error: float = PEOPLE_LABEL_ERROR
    _last: list[tuple[BehaviourPool, float]] = field(
        default_factory=list, init=False, repr=False, compare=False
    )
    """The last pool calibrated and its σ: a teacher asked one query at a time (continuous
    training) calibrates each pool once."""

    def sigma(self, pool: BehaviourPool) -> float:
        """The per-step noise σ for `pool`: the calibrated sd over the behaviour length."""
        if len(pool) == 0:
            return 0.0
        if self._last and self._last[0][0] is pool:
            return self._last[0][1]
        sigma = calibrated_noise_sd(pool.true_returns, self.label_error) / pool.fragments[0].length
        self._last[:] = [(pool, sigma)]
        return sigma

    def answer(
        self, pool: BehaviourPool, queries: Sequence[Query], rng: np.random.Generator
    ) -> list[Judgement]:
        return self.make(self.sigma(pool)).answer(pool, queries, rng)


def _untied_gaps(returns: FloatArray) -> FloatArray:
    """|R_i − R_j| of the pool's pairs with unequal returns (at most `MAX_PAIRS` of them)."""
    i, j = np.triu_indices(len(returns), k=1)
    if i.size > MAX_PAIRS:
        keep = np.linspace(0, i.size - 1, MAX_PAIRS).astype(np.int64)
        i, j = i[keep], j[keep]
    gaps = np.abs(returns[i] - returns[j])
    scale = max(float(np.abs(returns).max()), 1.0) if returns.size else 1.0
    return gaps[gaps > 1e-12 * scale]
