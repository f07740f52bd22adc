"""The agent's scores in words, as the summary texts, the README and the page show them."""

import math

from groupwise.agent_file.summary import TargetSummary


def format_value(value: float) -> str:
    """A value as the summary texts show it: 3 significant digits, thousands grouped (as the
    page's `formatValue`)."""
    rounded = value if abs(value) >= 1000 else float(f"{value:.3g}")
    # half up, as JavaScript's Math.round (Python's round goes to even)
    return f"{math.floor(rounded + 0.5):,}" if abs(rounded) >= 1000 else f"{rounded:g}"


def _decimals_at(value: float, digits: int) -> int:
    """Decimals of `value` written to `digits` significant figures (0 for a whole number)."""
    rounded = abs(float(f"{value:.{digits}g}"))
    return 0 if rounded == 0 else max(0, digits - 1 - math.floor(math.log10(rounded)))


def mean_sd(mean: float, sd: float | None) -> str:
    """ "mean ± sd", both to one decimal place: the sd's second significant figure, but no
    finer than the mean's third ("0.140 ± 0.001", not "0.14 ± 0.000621"; issue 40), as the
    page's `meanSd`; an sd below the last place shown is one unit of it."""
    if sd is None:
        return format_value(mean)
    if sd == 0 or not (math.isfinite(sd) and math.isfinite(mean)):
        return f"{format_value(mean)} ± {format_value(sd)}"
    places = (
        0
        if abs(mean) >= 1000
        else min(_decimals_at(sd, 2), 20 if mean == 0 else _decimals_at(mean, 3))
    )
    return f"{mean:,.{places}f} ± {max(abs(sd), 10.0**-places):,.{places}f}"


def score_text(
    target: TargetSummary | None,
    measure: str,
    true_return: tuple[float | None, float | None],
    target_score: tuple[float | None, float | None] = (None, None),
) -> str:
    """The evaluation in words: in a target env the episode score first, in its unit, with
    the threshold, then the per-step sum, e.g. "backward turns per episode 0.23 ± 0.05
    (threshold 1) · per-step sum 184 ± 3 rad/s"; else "true return 41.5 ± 3.2".
    `true_return` and `target_score` are (mean, sd); None: not measured."""

    mean, sd = true_return
    if target is None:
        return "not measured" if mean is None else f"{measure} {mean_sd(mean, sd)}"
    parts = []
    score, score_sd = target_score
    if score is not None:
        parts.append(
            f"{target.unit} per episode {mean_sd(score, score_sd)} "
            f"(threshold {format_value(target.threshold)})"
        )
    if mean is not None:
        parts.append(f"per-step sum {mean_sd(mean, sd)} {target.step_unit}")
    return " · ".join(parts) or "not measured"
