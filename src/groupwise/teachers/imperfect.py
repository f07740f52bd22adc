"""B-Pref-style imperfect teachers (Lee et al. 2021, "B-Pref"), for pair and group queries.

Each imperfection is one composable piece of a `SimulatedTeacher` (`group_decision.py`):

- myopic: `Perception(gamma=γ)`, earlier steps discounted by γ^(L−1−t) (B-Pref γ = 0.9);
- skip: `SkipWhenBothBelow(q)` before `decide`: skip when both groups' mean perceived
  returns lie below the q-quantile of the pool's true returns;
- equal: `EqualWhenClose(f)` before `decide`: label 0.5 (groups kept whole: "equal" has no
  wrong side) when the mean perceived returns differ by less than f pool standard
  deviations;
- mistake: `Mistake(ε)` after `decide`: flip a strict label with probability ε.

Combined, the order is B-Pref's: skip, equal, choice, mistake; an "equal" answer is never
flipped. B-Pref sets its skip and equal thresholds as a fraction of the mean segment return,
which means nothing for envs with negative returns (Reacher); we scale them by the pool's
true returns instead (a quantile for skip, the standard deviation for equal). Every rule
acts on the *perceived* returns, so the paper's noise (and myopia) applies on top of each
imperfection; use `TeacherConfig.noise_sigma = 0` for B-Pref's noise-free teachers.
"""

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from groupwise.preferences.judgement import EQUAL
from groupwise.teachers.group_decision import LabelState, Perception, SimulatedTeacher, decide


@dataclass(frozen=True)
class SkipWhenBothBelow:
    """Skip when both groups' mean perceived returns are below the pool's `quantile`."""

    quantile: float = 0.1

    def __post_init__(self) -> None:
        if not 0.0 <= self.quantile <= 1.0:
            raise ValueError(f"skip quantile must be in [0, 1], got {self.quantile}")

    def __call__(self, query: LabelState, rng: np.random.Generator) -> LabelState:
        del rng
        if query.label is not None or query.skipped:
            return query
        threshold = float(np.quantile(query.pool_returns, self.quantile))
        if max(query.seen_left.mean(), query.seen_right.mean()) < threshold:
            return replace(query, skipped=True)
        return query


@dataclass(frozen=True)
class EqualWhenClose:
    """Answer "equal" when the mean perceived returns differ by less than `fraction` × the
    standard deviation of the pool's true returns (never for a pool of equal returns)."""

    fraction: float = 0.1

    def __post_init__(self) -> None:
        if self.fraction < 0:
            raise ValueError(f"equal fraction must be >= 0, got {self.fraction}")

    def __call__(self, query: LabelState, rng: np.random.Generator) -> LabelState:
        del rng
        if query.label is not None or query.skipped:
            return query
        threshold = self.fraction * float(np.std(query.pool_returns))
        if abs(query.seen_left.mean() - query.seen_right.mean()) < threshold:
            return replace(query, label=EQUAL)
        return query


@dataclass(frozen=True)
class Mistake:
    """Flip a decided strict label (1 ↔ 0) with probability `rate`; "equal" stays."""

    rate: float = 0.1

    def __post_init__(self) -> None:
        if not 0.0 <= self.rate <= 1.0:
            raise ValueError(f"mistake rate must be in [0, 1], got {self.rate}")

    def __call__(self, query: LabelState, rng: np.random.Generator) -> LabelState:
        if query.label is None or query.label == EQUAL or query.skipped:
            return query
        if rng.random() < self.rate:
            return replace(query, label=1.0 - query.label)
        return query


@dataclass(frozen=True)
class Imperfection:
    """B-Pref's parameters (their defaults), shared by every imperfect teacher."""

    gamma: float = 0.9
    """Myopic discount per step back from the last."""
    mistake: float = 0.1
    """Probability of flipping a strict label."""
    skip_quantile: float = 0.1
    """Skip when both groups look worse than this quantile of the pool's true returns."""
    equal_fraction: float = 0.1
    """Answer equal when the means differ by less than this many pool standard deviations."""


def myopic(sigma: float, p: Imperfection) -> SimulatedTeacher:
    """Sees discounted returns (γ on earlier steps), otherwise the paper's DM."""
    return SimulatedTeacher(Perception(sigma, p.gamma))


def mistaken(sigma: float, p: Imperfection) -> SimulatedTeacher:
    """The paper's DM, then a flip with probability ε."""
    return SimulatedTeacher(Perception(sigma), (decide, Mistake(p.mistake)))


def skipping(sigma: float, p: Imperfection) -> SimulatedTeacher:
    """Skips queries whose groups both look bad, otherwise the paper's DM."""
    return SimulatedTeacher(Perception(sigma), (SkipWhenBothBelow(p.skip_quantile), decide))


def equal_when_close(sigma: float, p: Imperfection) -> SimulatedTeacher:
    """Answers equal when the groups look alike, otherwise the paper's DM."""
    return SimulatedTeacher(Perception(sigma), (EqualWhenClose(p.equal_fraction), decide))


TEACHERS: dict[str, Callable[[float, Imperfection], SimulatedTeacher]] = {
    "myopic": myopic,
    "mistake": mistaken,
    "skip": skipping,
    "equal": equal_when_close,
}
"""Imperfection name -> teacher factory from the noise σ per step and the parameters."""
