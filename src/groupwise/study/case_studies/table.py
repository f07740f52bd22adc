"""The case-study results table: one row per `groupwise case-study` run directory.

    python -m groupwise.study.case_studies.table RUN_DIR [RUN_DIR ...]

prints a Markdown table (target, DM, seed, comparisons, preference pairs, share of pairs
between behaviours of equal target score, label error on the others, the greedy policy's
target score after each round, success and stretch rates at the end, wall time), read
from each run's ``case-study.csv`` and ``summary.json``. Above it, the summary: per target
and DM, the seeds whose greedy policy succeeds (at least `SEED_SUCCESS` of its final
episodes reach the threshold) after the last round and as the take-away agent, the pairs and
comparisons used, and the spread and best of the pools' target scores in rounds 0–2
(`pool_scores.pool_scores`, mean over the seeds). A run's DM is labelled with the exploration
it ran with (`setup_label`). With ``--figure PNG`` it also draws each run's target score
against its preference pairs, one panel per target, the success threshold dashed; with
``--strips PNG`` the five-frame strip of each target's and DM's best final episode. It is how
``docs/results/case-studies/README.md`` and its figures were made.
"""

import argparse
import csv
import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from groupwise.config_history import REMOVED_FIELDS

HEADER = (
    "| target | DM | seed | comparisons | preference pairs | tied pairs | label error "
    "(untied) | target score after each round | success | stretch | wall |\n"
    "|---|---|---:|---:|---:|---:|---:|---|---:|---:|---:|"
)


SEED_SUCCESS = 0.6
"""A seed succeeds when this share of its final greedy episodes (3 of 5) reach the threshold."""

SUMMARY_HEADER = (
    "| target | DM | seeds | successful seeds, last round | as take-away agent | stretch "
    "| comparisons | preference pairs | pool sd, rounds 0–2 | pool max, rounds 0–2 |\n"
    "|---|---|---:|---:|---:|---:|---:|---:|---|---|"
)


SETUP_FIELDS: dict[tuple[str, str], Callable[[Any], str]] = {
    ("loop", "pool_size"): lambda size: f"pools of {size:,}",
    ("loop", "pool_variants"): lambda count: f"{count} pool variants",
    ("training", "pretrain_steps"): lambda steps: f"pre-training {steps:,}",
}
"""The config fields a run's label names when they are set (not None or 0), in order."""


def setup_label(run: Path) -> str:
    """The run's decision-maker with the setup it ran with (`SETUP_FIELDS`), e.g.
    "groupwise", "groupwise · 8 pool variants · pre-training 100,000", "groupwise · pools of
    500"; a run of a mechanism removed since (`config_history.REMOVED_FIELDS`) names the field and
    its value, e.g. "groupwise · 8 pool variants · adopt variants"."""
    summary, _ = _read(run)
    cfg = json.loads((run / "config.json").read_text())
    parts = [summary["decision_maker"]]
    for (section, name), label in SETUP_FIELDS.items():
        if value := cfg.get(section, {}).get(name):
            parts.append(label(value))
    for section, removed in REMOVED_FIELDS.items():
        for name, default in removed.items():
            value = cfg.get(section, {}).get(name, default)
            if value != default:
                parts.append(_removed_label(name, value))
    return " · ".join(parts)


def _removed_label(name: str, value: Any) -> str:
    """ "adopt variants", "pool lookahead 40,960", "suggestion rank optimistic"."""
    words = name.replace("_", " ")
    if value is True:
        return words
    return f"{words} {value:,g}" if isinstance(value, int | float) else f"{words} {value}"


def _pool_means(rows_of_runs: Sequence[list[dict[str, str]]], column: str) -> str:
    """Per round 0–2 the mean over the runs of `column` ("–" where no run has it: fewer
    rounds, or a run that predates the column)."""
    means = []
    for r in range(3):
        values = [
            float(rows[r][column]) for rows in rows_of_runs if r < len(rows) and column in rows[r]
        ]
        means.append(f"{sum(values) / len(values):.2f}" if values else "–")
    return " / ".join(means)


def summary_rows(runs: Sequence[Path]) -> list[str]:
    """One Markdown row per target and DM of `runs` (module docstring), in order of first
    appearance."""
    cells: dict[tuple[str, str], list[tuple[dict[str, Any], list[dict[str, str]]]]] = {}
    for run in runs:
        summary, rows_of_run = _read(run)
        key = (summary["target"]["name"], setup_label(run))
        cells.setdefault(key, []).append((summary, rows_of_run))
    rows = []
    for (target, dm), read in cells.items():
        summaries = [summary for summary, _ in read]
        early = [rows_of_run for _, rows_of_run in read]
        last = sum(s["final"]["success_rate"] >= SEED_SUCCESS for s in summaries)
        kept = sum(s.get("takeaway", s["final"])["success_rate"] >= SEED_SUCCESS for s in summaries)
        stretch = sum(s["final"]["stretch_rate"] >= SEED_SUCCESS for s in summaries)
        n = len(summaries)
        rows.append(
            f"| {target} | {dm} | {n} | **{last}/{n}** | {kept}/{n} | {stretch}/{n} "
            f"| {_span(s['comparisons'] for s in summaries)} "
            f"| {_span(s['preference_pairs'] for s in summaries)} "
            f"| {_pool_means(early, 'pool_score_sd')} | {_pool_means(early, 'pool_score_max')} |"
        )
    return rows


def _span(values: Any) -> str:
    low, high = min(values := list(values)), max(values)
    return f"{low:,}" if low == high else f"{low:,}–{high:,}"


def _read(run: Path) -> tuple[dict[str, Any], list[dict[str, str]]]:
    """A run's ``summary.json`` and the rows of its ``case-study.csv``."""
    summary = json.loads((run / "summary.json").read_text())
    with (run / "case-study.csv").open() as handle:
        return summary, list(csv.DictReader(handle))


def markdown_row(run: Path) -> str:
    """The table row of one case-study run directory."""
    summary, rows = _read(run)
    last = rows[-1]
    seed = json.loads((run / "config.json").read_text())["loop"]["seed"]
    scores = ", ".join(f"{float(r['target_score_mean']):.2f}" for r in rows)
    final = summary["final"]
    episodes = len(final["scores"])
    ties, error = "–", "–"  # no pairs: nothing tied, nothing labelled
    if int(last["pairs_total"]):
        ties = f"{float(last['tied_share_total']):.2f}"
        error = f"{float(last['label_error_untied_total']):.2f}"
    success = round(final["success_rate"] * episodes)
    stretch = round(final["stretch_rate"] * episodes)
    return (
        f"| {summary['target']['name']} | {setup_label(run)} | {seed} "
        f"| {int(last['comparisons_total'])} | {int(last['pairs_total']):,} "
        f"| {ties} | {error} "
        f"| {scores} | {success}/{episodes} | {stretch}/{episodes} "
        f"| {float(last['wall_s']):.0f} s |"
    )


def curves_figure(runs: Sequence[Path], path: Path) -> Path:
    """Target score (mean over the evaluation episodes) against preference pairs so far,
    one line per run, one panel per target; the success threshold dashed. Needs
    Matplotlib (the ``study`` extra), imported here so the table alone does not."""
    curves = []
    for summary, rows in (_read(run) for run in runs):
        pairs = [float(r["pairs_total"]) for r in rows]
        scores = [float(r["target_score_mean"]) for r in rows]
        target = summary["target"]
        curves.append(
            Curve(target["name"], target["threshold"], summary["decision_maker"], pairs, scores)
        )
    return target_curves_figure(curves, path, "preference pairs")


@dataclass(frozen=True)
class Curve:
    """One run's line in `target_curves_figure`: its target's score against `x`."""

    target: str
    threshold: float
    """The target's success threshold (dashed)."""
    key: str
    """What colours the line (the DM, the training mode): one colour and legend entry a key."""
    x: Sequence[float]
    scores: Sequence[float]


def target_curves_figure(curves: Sequence[Curve], path: Path, xlabel: str) -> Path:
    """Target score against `xlabel`, one panel per target (in the order they first come),
    one line per curve coloured by its key, the target's success threshold dashed, written
    to `path`. Needs Matplotlib (the ``study`` extra), imported here."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    def style(i: int) -> dict[str, Any]:  # ten colours, then dashed
        return {"marker": "o", "ms": 3, "color": f"C{i % 10}", "ls": "-" if i < 10 else "--"}

    targets = {curve.target: curve.threshold for curve in curves}
    keys = list(dict.fromkeys(curve.key for curve in curves))
    columns = 1 if len(keys) <= 2 else 2  # one legend below the panels, whatever its length
    height = 3.4 + 0.2 * -(-len(keys) // columns)
    figure = Figure(figsize=(max(4.2 * len(targets), 8.4), height), dpi=120, layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.subplots(1, len(targets), squeeze=False)[0]
    for ax, (target, threshold) in zip(axes, targets.items(), strict=True):
        for curve in (c for c in curves if c.target == target):
            ax.plot(curve.x, curve.scores, **style(keys.index(curve.key)))
        ax.axhline(threshold, color="0.4", ls="--", lw=0.8)
        ax.set_title(target)
        ax.set_xlabel(xlabel)
        ax.set_ylabel("target score (greedy policy)")
    handles = [Line2D([], [], **style(i)) for i in range(len(keys))]
    figure.legend(handles, keys, loc="outside lower center", ncols=columns, frameon=False,
                  fontsize=8)  # fmt: skip
    figure.savefig(path)
    return path


def strips_figure(runs: Sequence[Path], path: Path) -> Path:
    """The five-frame strip (``strip.png``) of each target's and DM's run with the best filmed
    episode, one row each, titled with the run's seed and final success. Needs Matplotlib.

    Raises:
        ValueError: no run has a strip (they ran with ``--no-video``).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from PIL import Image

    best: dict[tuple[str, str], tuple[float, Path, dict[str, Any]]] = {}
    for run in runs:
        summary, _ = _read(run)
        if not (run / "strip.png").is_file() or "filmed" not in summary:
            continue
        key = (summary["target"]["name"], summary["decision_maker"])
        score = float(summary["filmed"]["score"])
        if key not in best or score > best[key][0]:
            best[key] = (score, run, summary)
    if not best:
        raise ValueError("no run has a strip.png (run without --no-video)")
    figure = Figure(figsize=(10, 2.3 * len(best)), dpi=72, layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.subplots(len(best), 1, squeeze=False)[:, 0]
    for ax, ((target, dm), (score, run, summary)) in zip(axes, sorted(best.items()), strict=True):
        ax.imshow(Image.open(run / "strip.png"))
        ax.set_axis_off()
        seed = json.loads((run / "config.json").read_text())["loop"]["seed"]
        ax.set_title(
            f"{target}, {dm}, seed {seed}: best final episode {score:.2f} "
            f"{summary['target']['unit']}, success {summary['final']['success_rate']:.0%}",
            fontsize=9,
        )
    figure.savefig(path)
    return path


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", nargs="+", type=Path, help="case-study output directories")
    parser.add_argument("--figure", type=Path, help="also draw the curves into this PNG")
    parser.add_argument("--strips", type=Path, help="also put the best strips into this PNG")
    args = parser.parse_args(argv)
    if args.figure:
        curves_figure(args.runs, args.figure)
    if args.strips:
        strips_figure(args.runs, args.strips)
    print(SUMMARY_HEADER)
    print("\n".join(summary_rows(args.runs)))
    print()
    print(HEADER)
    for run in args.runs:
        print(markdown_row(run))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
