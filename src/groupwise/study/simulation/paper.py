"""The paper's simulation-study numbers (Kompatscher et al., EuroVis 2025, §5; SPEC §8).

Keyed by our env names and DM registry names, for printing beside our results. The paper's
PPO budgets and implementation (the authors' prototype) differ from ours, so its numbers are
context, not targets.
"""

from dataclasses import dataclass


@dataclass(frozen=True)
class PaperTest:
    """A t-test the paper reports between two DMs' pooled values."""

    t: float
    p: float
    relative: float | None = None
    """The paper's "x % higher", as a fraction (0.693 for +69.3 %), where it gives one."""


TABLE1: dict[str, dict[str, tuple[float, float]]] = {
    "Hopper": {"pairwise": (1221, 471), "groupwise": (1754, 851), "interactive": (2053, 443)},
    "HalfCheetah": {"pairwise": (579, 195), "groupwise": (1372, 799), "interactive": (1269, 1583)},
    "Walker2d": {"pairwise": (92, 155), "groupwise": (118, 268), "interactive": (603, 642)},
    "Reacher": {"pairwise": (-280, 110), "groupwise": (-239, 78), "interactive": (-202, 49)},
    "MountainCarContinuous": {
        "pairwise": (18059, 389),
        "groupwise": (18363, 263),
        "interactive": (18259, 261),
    },
    "GridWorld": {"pairwise": (762, 85), "groupwise": (712, 23), "interactive": (770, 31)},
}
"""Table 1: final true return, (mean, SD) over 5 runs, per env and DM."""

PREFERENCE_PAIRS: dict[str, float] = {"pairwise": 400, "interactive": 690, "groupwise": 1209}
"""Mean preference pairs per run."""

NORMALISED_TESTS: dict[tuple[str, str], PaperTest] = {
    ("interactive", "pairwise"): PaperTest(t=2.684, p=9.456e-3, relative=0.693),
    ("groupwise", "pairwise"): PaperTest(t=1.636, p=1.072e-1, relative=0.413),
    ("interactive", "groupwise"): PaperTest(t=1.147, p=2.560e-1, relative=0.280),
}
"""Normalised final returns pooled over envs, (a, b) tests mean(a) − mean(b)."""

PAIR_TESTS: dict[tuple[str, str], PaperTest] = {
    ("groupwise", "pairwise"): PaperTest(t=2.663, p=1.129e-2),
    ("interactive", "pairwise"): PaperTest(t=1.033, p=3.083e-1),
    ("interactive", "groupwise"): PaperTest(t=-2.107, p=4.175e-2),
}
"""Preference pairs per run, (a, b) tests mean(a) − mean(b)."""

CAPPED_MEANS: dict[str, tuple[float, float]] = {
    "pairwise": (0.582, 0.780),
    "groupwise": (-0.003, 1.238),
    "interactive": (0.920, 0.650),
}
"""Capped-pairs ablation: normalised final return, (mean, SD) pooled over envs."""

CAPPED_TESTS: dict[tuple[str, str], PaperTest] = {
    ("groupwise", "pairwise"): PaperTest(t=-2.154, p=3.544e-2),
    ("interactive", "pairwise"): PaperTest(t=1.792, p=7.834e-2),
    ("interactive", "groupwise"): PaperTest(t=3.555, p=7.601e-4),
}
"""Capped-pairs ablation, (a, b) tests mean(a) − mean(b)."""


def paper_test(
    tests: dict[tuple[str, str], PaperTest], a: str, b: str
) -> tuple[PaperTest, float] | None:
    """The paper's test of a vs b and the sign to apply (−1 when it tested b vs a)."""
    if (a, b) in tests:
        return tests[(a, b)], 1.0
    if (b, a) in tests:
        return tests[(b, a)], -1.0
    return None
