"""How a simulated decision-maker perceives returns (paper eq. 1, SPEC §7)."""

import numpy as np

from groupwise.types import FloatArray


def perceived_returns(
    true_returns: FloatArray, length: int, sigma: float, rng: np.random.Generator
) -> FloatArray:
    """True returns plus ε ~ Normal(0, (L·σ)²), drawn once per behaviour per judgement.

    σ is the noise per step (default 0.25) and L the fragment length, so the noise grows
    with the window a person watches.
    """
    if sigma < 0:
        raise ValueError(f"noise sigma must be >= 0, got {sigma}")
    true_returns = np.asarray(true_returns, dtype=np.float64)
    return true_returns + rng.normal(0.0, length * sigma, size=true_returns.shape)


def preference(
    perceived_a: float, perceived_b: float, rng: np.random.Generator, beta: float | None = None
) -> float:
    """1.0 if a is preferred, 0.0 if b is, 0.5 when exactly equal.

    With `beta` (a temperature) the choice is Boltzmann-rational:
    P(a) = σ((R(a) − R(b)) / β); without it the higher perceived return wins.
    """
    diff = perceived_a - perceived_b
    if beta is None:
        return 1.0 if diff > 0 else 0.0 if diff < 0 else 0.5
    if beta <= 0:
        raise ValueError(f"Boltzmann temperature must be > 0, got {beta}")
    p = 1.0 / (1.0 + np.exp(-diff / beta))
    return 1.0 if rng.random() < p else 0.0
