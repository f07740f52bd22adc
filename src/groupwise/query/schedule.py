"""How many comparisons each round asks for (SPEC §3, query schedule)."""

from collections.abc import Callable

import numpy as np

SCHEDULES: dict[str, Callable[[int], float]] = {
    "constant": lambda t: 1.0,
    "hyperbolic": lambda t: 1.0 / (1.0 + t),
    "inverse_quadratic": lambda t: 1.0 / (1.0 + t**2),
}
"""Relative weight of round t = 1, 2, ... among the rounds after round 0."""


def comparisons_per_round(
    total: int, rounds: int, initial_fraction: float = 0.1, schedule: str = "constant"
) -> list[int]:
    """Split `total` comparisons over `rounds` rounds; the list sums to `total` exactly.

    Round 0 gets `initial_fraction` of the total (at least one comparison); the rest is
    spread over rounds 1 … rounds−1 by the schedule's weights (largest-remainder rounding).
    With a single round everything is asked in round 0.
    """
    if total < 1 or rounds < 1:
        raise ValueError(f"need total >= 1 and rounds >= 1, got total={total}, rounds={rounds}")
    if not 0.0 < initial_fraction <= 1.0:
        raise ValueError(f"initial fraction must be in (0, 1], got {initial_fraction}")
    if schedule not in SCHEDULES:
        raise ValueError(f"unknown schedule {schedule!r}; choose from {sorted(SCHEDULES)}")
    if rounds == 1:
        return [total]
    first = max(1, round(total * initial_fraction))
    rest = total - first
    weights = np.array([SCHEDULES[schedule](t) for t in range(1, rounds)])
    exact = rest * weights / weights.sum()
    counts = np.floor(exact).astype(int)
    order = np.argsort(-(exact - counts), kind="stable")
    counts[order[: rest - counts.sum()]] += 1
    return [first, *counts.tolist()]
