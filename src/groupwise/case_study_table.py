"""The case-study results table: one row per `groupwise case-study` run directory.

    python -m groupwise.case_study_table RUN_DIR [RUN_DIR ...]

prints a Markdown table (target, DM, seed, comparisons, preference pairs, share of pairs
between behaviours of equal target score, label error on the others, the greedy policy's
target score after each round, success and stretch rates at the end, wall time), read
from each run's ``case-study.csv`` and ``summary.json`` and, for the ties, its last
checkpoint's preference dataset. It is how ``docs/results/case-studies/README.md`` was made.
"""

import argparse
import csv
import json
from pathlib import Path

from groupwise.preferences.dataset import PreferenceDataset

HEADER = (
    "| target | DM | seed | comparisons | preference pairs | tied pairs | label error "
    "(untied) | target score after rounds 0 … 4 | success | stretch | wall |\n"
    "|---|---|---:|---:|---:|---:|---:|---|---:|---:|---:|"
)


def markdown_row(run: Path) -> str:
    """The table row of one case-study run directory."""
    summary = json.loads((run / "summary.json").read_text())
    with (run / "case-study.csv").open() as handle:
        rows = list(csv.DictReader(handle))
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


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", nargs="+", type=Path, help="case-study output directories")
    args = parser.parse_args(argv)
    print(HEADER)
    for run in args.runs:
        print(markdown_row(run))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
