"""The case-study results table: one row per `groupwise case-study` run directory.

    python -m groupwise.study.case_study_table RUN_DIR [RUN_DIR ...]

prints a Markdown table (target, DM, seed, comparisons, preference pairs, share of pairs
between behaviours of equal target score, label error on the others, the greedy policy's
target score after each round, success and stretch rates at the end, wall time), read
from each run's ``case-study.csv`` and ``summary.json`` and, for the ties, its last
checkpoint's preference dataset. With ``--figure PNG`` it also draws each run's target score against
its preference pairs, one panel per target, the success threshold dashed. It is how
``docs/results/case-studies/README.md`` and its ``curves.png`` were made.
"""

import argparse
import csv
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from groupwise.preferences.dataset import PreferenceDataset

HEADER = (
    "| target | DM | seed | comparisons | preference pairs | tied pairs | label error "
    "(untied) | target score after each round | success | stretch | wall |\n"
    "|---|---|---:|---:|---:|---:|---:|---|---:|---:|---:|"
)


def _read(run: Path) -> tuple[dict[str, Any], list[dict[str, str]]]:
    """A run's ``summary.json`` and the rows of its ``case-study.csv``."""
    summary = json.loads((run / "summary.json").read_text())
    with (run / "case-study.csv").open() as handle:
        return summary, list(csv.DictReader(handle))


def markdown_row(run: Path) -> str:
    """The table row of one case-study run directory."""
    summary, rows = _read(run)
    last = rows[-1]
    checkpoints = sorted((run / "checkpoints").glob("round-*"))
    dataset = PreferenceDataset.load(checkpoints[-1] / "dataset.npz")
    seed = json.loads((run / "config.json").read_text())["loop"]["seed"]
    scores = ", ".join(f"{float(r['target_score_mean']):.2f}" for r in rows)
    final = summary["final"]
    episodes = len(final["scores"])
    success = round(final["success_rate"] * episodes)
    stretch = round(final["stretch_rate"] * episodes)
    return (
        f"| {summary['target']['name']} | {summary['decision_maker']} | {seed} "
        f"| {int(last['comparisons_total'])} | {int(last['pairs_total']):,} "
        f"| {dataset.tied().mean():.2f} | {dataset.label_error_rate(untied=True):.2f} "
        f"| {scores} | {success}/{episodes} | {stretch}/{episodes} "
        f"| {float(last['wall_s']):.0f} s |"
    )


def curves_figure(runs: Sequence[Path], path: Path) -> Path:
    """Target score (mean over the evaluation episodes) against preference pairs so far,
    one line per run, one panel per target; the success threshold dashed. Needs
    Matplotlib (the ``study`` extra), imported here so the table alone does not."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    read = [_read(run) for run in runs]
    targets = {s["target"]["name"]: s["target"]["threshold"] for s, _ in read}
    dms = list(dict.fromkeys(s["decision_maker"] for s, _ in read))
    figure = Figure(figsize=(4.2 * len(targets), 3.4), dpi=120, layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.subplots(1, len(targets), squeeze=False)[0]
    colours = {dm: f"C{k}" for k, dm in enumerate(dms)}
    for ax, (target, threshold) in zip(axes, targets.items(), strict=True):
        shown: set[str] = set()
        for summary, rows in read:
            dm = summary["decision_maker"]
            if summary["target"]["name"] != target:
                continue
            pairs = [float(r["pairs_total"]) for r in rows]
            scores = [float(r["target_score_mean"]) for r in rows]
            ax.plot(pairs, scores, marker="o", ms=3, color=colours[dm],
                    label=None if dm in shown else dm)  # fmt: skip
            shown.add(dm)
        ax.axhline(threshold, color="0.4", ls="--", lw=0.8)
        ax.set_title(target)
        ax.set_xlabel("preference pairs")
        ax.set_ylabel("target score (greedy policy)")
        ax.legend(frameon=False, fontsize=8)
    figure.savefig(path)
    return path


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", nargs="+", type=Path, help="case-study output directories")
    parser.add_argument("--figure", type=Path, help="also draw the curves into this PNG")
    args = parser.parse_args(argv)
    if args.figure:
        curves_figure(args.runs, args.figure)
    print(HEADER)
    for run in args.runs:
        print(markdown_row(run))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
