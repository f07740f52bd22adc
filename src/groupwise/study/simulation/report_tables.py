"""Markdown pieces of the study report: numbers, rows, per-cell statistics and the table
of Welch t-tests between DMs beside the paper's (`report` assembles them)."""

import math
from collections.abc import Mapping

import numpy as np

from groupwise.study.simulation import paper
from groupwise.study.simulation.results import Grid
from groupwise.study.simulation.statistics import mean_sd, relative_difference, welch_t_test

DASH = "–"
ALL_PAIRS_UP_TO = 6
"""With more DMs than this, each is tested against the first only (the table stays short)."""


def finite_column(grid: Grid, env: str, dm: str) -> np.ndarray:
    """The finite values of (env, dm) in `grid` (empty when it has none)."""
    if env not in grid.envs or dm not in grid.dms:
        return np.empty(0)
    column = grid.values[dm][:, grid.envs.index(env)]
    return column[np.isfinite(column)]


def mean_sd_n(grid: Grid, env: str, dm: str) -> str:
    values = finite_column(grid, env, dm)
    if not values.size:
        return DASH
    mean, sd = mean_sd(values)
    return f"{fmt_num(mean, 1)} ± {fmt_num(sd, 1)} (n={values.size})"


def pooled_mean(grid: Grid, dm: str, envs: tuple[str, ...]) -> str:
    values = np.concatenate([finite_column(grid, env, dm) for env in envs])
    return fmt_num(float(values.mean()), 1) if values.size else DASH


def tests_table(
    values: Mapping[str, np.ndarray],
    dms: tuple[str, ...],
    cited: Mapping[tuple[str, str], paper.PaperTest],
    digits: int,
) -> str:
    lines = [md_row(["a vs b", "mean a − b", "a vs b (%)", "t", "df", "p", "paper"])]
    lines.append(md_row(["---"] * 7))
    for a, b in comparisons(dms):
        test = welch_t_test(values[a], values[b])
        mean_a, mean_b = mean_sd(values[a])[0], mean_sd(values[b])[0]
        relative = relative_difference(mean_a, mean_b)
        found = paper.paper_test(dict(cited), a, b)
        reference = paper_reference(found[0], found[1]) if found else DASH
        lines.append(
            md_row(
                [
                    f"{a} vs {b}",
                    fmt_num(mean_a - mean_b, digits),
                    fmt_num(100 * relative, 1),
                    fmt_num(test.t, 3),
                    fmt_num(test.df, 1),
                    fmt_num(test.p, 3, general=True),
                    reference,
                ]
            )
        )
    return "\n".join(lines) if len(lines) > 2 else "Only one DM: nothing to test."


def comparisons(dms: tuple[str, ...]) -> list[tuple[str, str]]:
    """(a, b) pairs to test: every pair of up to `ALL_PAIRS_UP_TO` DMs (later vs earlier, so
    the baseline, first in the registry, is b), else each DM against the first."""
    if len(dms) <= ALL_PAIRS_UP_TO:
        return [(a, b) for i, b in enumerate(dms) for a in dms[i + 1 :]]
    return [(a, dms[0]) for a in dms[1:]]


def paper_reference(test: paper.PaperTest, sign: float) -> str:
    text = f"t = {sign * test.t:.3f}, p = {test.p:.3g}"
    if test.relative is not None and sign > 0:
        text += f", {100 * test.relative:+.1f} %"
    return text


def fmt_num(value: float, digits: int, general: bool = False) -> str:
    if value is None or not math.isfinite(value):
        return DASH
    return f"{value:.{digits}g}" if general else f"{value:.{digits}f}"


def md_row(cells: list[str]) -> str:
    return "| " + " | ".join(cells) + " |"
