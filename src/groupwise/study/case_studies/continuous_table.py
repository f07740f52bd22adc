"""Rounds against continuous training with a timed teacher: the table and figure of
``docs/results/continuous`` (issue 24).

    python -m groupwise.study.case_studies.continuous_table RUN_DIR [RUN_DIR ...] [--figure PNG]
                                                            [--marks 10 20] [--table CSV]
    python -m groupwise.study.case_studies.continuous_table RUN_DIR ... --append-to CSV
                                                            --variant NAME

Each RUN_DIR is a ``groupwise case-study … --teacher-pace S`` run (`--training rounds` or
`continuous`). Its rounds carry the teacher's virtual clock (``clock_s`` in ``rounds.csv``:
the teacher's seconds, plus in rounds mode the seconds the teacher waited for PPO at
`ppo_steps_per_s`) and the greedy policy's target score and success rate after the round
(``case-study.csv``). Printed: one row per run (score after each round at its minute), then
per target, mode and variant (`variants`: the settings that set a run apart from most of
the runs given, e.g. ``reward.use_actions=True`` in an ablation's arm, or "as most": the
arms' common settings) the minutes until the target was passed
— the first round whose success rate reaches `SUCCESS_SHARE` of the evaluation episodes,
as the case studies count success — or that it was not, and within how many minutes. With
`--marks`, a second table: per target, mode and variant, how many runs pass at each mark
(the last round ended by it, `success_at`) and how many passed at some round by it.
"""

import argparse
import csv
import json
import math
import statistics
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from groupwise.envs import TARGETS
from groupwise.study.case_studies.table import Curve, target_curves_figure

SUCCESS_SHARE = 0.6
"""A round passes when at least this share of its evaluation episodes reach the threshold
(3 of 5, as `case_study_table` counts success)."""
MARK_GRACE_MIN = 0.25
"""A round ended by a mark of M minutes ends within M + this: rounds of whole comparisons
seldom end on the minute (63 of the stand-up's at the paper's 9.47 s are 9.9 min, 64 are
10.1), and 15 s is under two comparisons at the paper's pace."""


@dataclass(frozen=True)
class TimedRun:
    """One timed case-study run: per round the teacher's clock, score and success rate."""

    target: str
    unit: str
    threshold: float
    mode: str
    config: Mapping[str, Any]
    """The run's settings, flattened: "ppo.standardise_reward" → False."""
    seed: int
    minutes: tuple[float, ...]
    scores: tuple[float, ...]
    success: tuple[float, ...]
    env_steps: int

    @property
    def passed_at(self) -> float | None:
        """Minutes of the teacher's clock at the first passing round, or None."""
        return minutes_to_pass(self.minutes, self.success)


def minutes_to_pass(minutes: Sequence[float], success: Sequence[float]) -> float | None:
    """The clock (minutes) of the first round whose success rate reaches `SUCCESS_SHARE`,
    or None when no round does."""
    for clock, rate in zip(minutes, success, strict=True):
        if rate >= SUCCESS_SHARE - 1e-9:
            return clock
    return None


def success_at(minutes: Sequence[float], success: Sequence[float], mark: float) -> float | None:
    """The success rate of the last round ended by `mark` minutes (within
    `MARK_GRACE_MIN`), or None when none had."""
    ended = [
        rate for clock, rate in zip(minutes, success, strict=True) if clock <= mark + MARK_GRACE_MIN
    ]
    return ended[-1] if ended else None


def read_run(run: Path) -> TimedRun:
    """A run directory's `TimedRun`.

    Raises:
        ValueError: the run had no timed teacher (no ``clock_s``), or has not finished.
    """
    if not (run / "summary.json").is_file():
        raise ValueError(f"{run}: no summary.json (not a finished case-study run)")
    summary = json.loads((run / "summary.json").read_text())
    config = json.loads((run / "config.json").read_text())
    with (run / "rounds.csv").open() as handle:
        rounds = list(csv.DictReader(handle))
    with (run / "case-study.csv").open() as handle:
        scored = list(csv.DictReader(handle))
    clocks = [float(r.get("clock_s") or "nan") for r in rounds]
    if not clocks or any(math.isnan(c) for c in clocks):
        raise ValueError(f"{run}: no teacher clock (run it with --teacher-pace)")
    return TimedRun(
        target=summary["target"]["name"],
        unit=summary["target"]["unit"],
        threshold=float(summary["target"]["threshold"]),
        mode=config["training"]["mode"],
        config=flat_settings(config),
        seed=int(config["loop"]["seed"]),
        minutes=tuple(c / 60.0 for c in clocks),
        scores=tuple(float(r["target_score_mean"]) for r in scored),
        success=tuple(float(r["success_rate"]) for r in scored),
        env_steps=int(summary["env_steps"]),
    )


TABLE_COLUMNS = (
    "target",
    "training",
    "variant",
    "seed",
    "round",
    "minute",
    "env_steps",
    "target_score",
    "success",
)
"""The columns of a tidy rounds table this module reads back (`read_table`)."""
TABLE_EXTRA = {
    "comparisons": "comparisons_total",
    "judgements": "judgements_total",
    "env_steps": "env_steps",
    "target_score": "target_score_mean",
    "success": "success_rate",
    "pool_score_max": "pool_score_max",
    "tied_share_total": "tied_share_total",
}
"""The columns `write_table` copies from a run's ``case-study.csv`` (table's: run's)."""


def write_table(runs: Sequence[Path], variant: str, path: Path) -> int:
    """Append the rounds of finished timed case-study `runs` to the tidy rounds table at
    `path` (written with its header when new), each run's rows named `variant` (the code it
    ran, e.g. "default (kept policy)"): `TABLE_COLUMNS` and `TABLE_EXTRA`. Returns the rows
    written.

    Raises:
        ValueError: a run has not finished, or had no timed teacher.
    """
    rows = []
    for run in runs:
        timed = read_run(run)
        with (run / "case-study.csv").open() as handle:
            scored = list(csv.DictReader(handle))
        for index, (minute, row) in enumerate(zip(timed.minutes, scored, strict=True)):
            rows.append({
                "target": timed.target, "training": timed.mode, "variant": variant,
                "seed": timed.seed, "round": index, "minute": round(minute, 2),
                **{ours: row.get(theirs, "") for ours, theirs in TABLE_EXTRA.items()},
            })  # fmt: skip
    new = not path.is_file() or path.stat().st_size == 0
    if new:
        columns = [*TABLE_COLUMNS[: TABLE_COLUMNS.index("minute") + 1], *TABLE_EXTRA]
    else:  # the table's own order
        with path.open() as handle:
            columns = next(csv.reader(handle))
    with path.open("a", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=columns, extrasaction="ignore")
        if new:
            writer.writeheader()
        writer.writerows(rows)
    return len(rows)


def read_table(path: Path) -> list[TimedRun]:
    """The runs of a tidy rounds table (`TABLE_COLUMNS`, more allowed; one row per round of a
    run, e.g. ``docs/results/continuous/headless/rounds.csv``): the run folders themselves
    are artifacts, not kept. A run's `config` is its ``variant`` alone.

    Raises:
        ValueError: a column is missing, or a target is unknown.
    """
    with path.open() as handle:
        rows = list(csv.DictReader(handle))
    missing = set(TABLE_COLUMNS) - set(rows[0] if rows else TABLE_COLUMNS)
    if missing:
        raise ValueError(f"{path}: no column {', '.join(sorted(missing))}")
    runs: dict[tuple[str, str, str, int], list[dict[str, str]]] = {}
    for row in rows:
        key = (row["target"], row["training"], row["variant"], int(row["seed"]))
        runs.setdefault(key, []).append(row)
    read = []
    for (name, mode, variant, seed), rounds in runs.items():
        if name not in TARGETS:
            raise ValueError(f"{path}: unknown target {name!r}")
        target = TARGETS[name]
        rounds.sort(key=lambda r: int(r["round"]))
        read.append(
            TimedRun(
                target=name,
                unit=target.unit,
                threshold=target.threshold,
                mode=mode,
                config={"variant": variant},
                seed=seed,
                minutes=tuple(float(r["minute"]) for r in rounds),
                scores=tuple(float(r["target_score"]) for r in rounds),
                success=tuple(float(r["success"]) for r in rounds),
                env_steps=int(rounds[-1]["env_steps"]),
            )
        )
    return read


SAME_ARM = frozenset({"loop.seed", "training.mode"})
"""Settings runs of one variant differ in: the seed, and the mode (a column of its own)."""


def flat_settings(config: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """A run's ``config.json`` as dotted keys, lists as tuples: {"ppo.gamma": 0.99, ...}."""
    flat: dict[str, Any] = {}
    for key, value in config.items():
        if isinstance(value, Mapping):
            flat |= flat_settings(value, f"{prefix}{key}.")
        else:
            flat[f"{prefix}{key}"] = tuple(value) if isinstance(value, list) else value
    return flat


def variants(runs: Sequence["TimedRun"]) -> list[str]:
    """Each run's variant: the settings in which it differs from most of `runs` (the most
    common value of each setting, the seed and mode aside), "key=value, ..." in key order,
    or "as most" when it differs in none. The arms of an ablation run beside its
    defaults are told apart without naming them."""
    keys = sorted({key for run in runs for key in run.config} - SAME_ARM)
    common = {
        key: Counter(repr(run.config.get(key)) for run in runs).most_common(1)[0][0] for key in keys
    }
    return [
        ", ".join(
            f"{key}={run.config.get(key)}"
            for key in keys
            if repr(run.config.get(key)) != common[key]
        )
        or "as most"
        for run in runs
    ]


def run_rows(runs: Sequence[TimedRun], labels: Sequence[str]) -> list[str]:
    """The per-run table (Markdown lines); `labels`, each run's variant."""
    lines = [
        "| target | training | variant | seed | PPO steps | target score after each "
        "round (at the teacher's minute) | passed at |",
        "|---|---|---|---:|---:|---|---:|",
    ]
    for run, label in zip(runs, labels, strict=True):
        points = ", ".join(
            f"{score:.2f} ({clock:.1f})"
            for score, clock in zip(run.scores, run.minutes, strict=True)
        )
        passed = "–" if run.passed_at is None else f"{run.passed_at:.1f} min"
        lines.append(
            f"| {run.target} | {run.mode} | {label} | {run.seed} | {run.env_steps:,} "
            f"| {points} | {passed} |"
        )
    return lines


def summary_rows(runs: Sequence[TimedRun], labels: Sequence[str]) -> list[str]:
    """Per target, mode and variant (`labels`, each run's): runs, final score (mean ± sd),
    runs passed and the minutes they needed (Markdown lines)."""
    lines = [
        "| target | training | variant | runs | PPO steps (mean) | final score, mean ± sd "
        "| passed | minutes to pass |",
        "|---|---|---|---:|---:|---|---:|---|",
    ]
    groups: dict[tuple[str, str, str], list[TimedRun]] = {}
    for run, label in zip(runs, labels, strict=True):
        groups.setdefault((run.target, run.mode, label), []).append(run)
    for (target, mode, variant), members in groups.items():
        finals = [m.scores[-1] for m in members]
        sd = statistics.stdev(finals) if len(finals) > 1 else 0.0
        passed = [m.passed_at for m in members if m.passed_at is not None]
        horizon = max(m.minutes[-1] for m in members)
        when = (
            ", ".join(f"{p:.1f}" for p in passed)
            if passed
            else f"not passed within {horizon:.1f} min"
        )
        steps = statistics.mean(m.env_steps for m in members)
        lines.append(
            f"| {target} | {mode} | {variant} | {len(members)} | {steps:,.0f} "
            f"| {statistics.mean(finals):.2f} ± {sd:.2f} {members[0].unit} "
            f"| {len(passed)}/{len(members)} | {when} |"
        )
    return lines


def mark_rows(runs: Sequence[TimedRun], labels: Sequence[str], marks: Sequence[float]) -> list[str]:
    """Per target, mode and variant: the runs passing at each mark (`success_at`) and those
    that passed at some round by it (Markdown lines)."""
    heads = " | ".join(f"passing at {m:g} min | passed by {m:g} min" for m in marks)
    lines = [
        f"| target | training | variant | runs | {heads} |",
        "|---|---|---|---:|" + "---:|" * (2 * len(marks)),
    ]
    groups: dict[tuple[str, str, str], list[TimedRun]] = {}
    for run, label in zip(runs, labels, strict=True):
        groups.setdefault((run.target, run.mode, label), []).append(run)
    for (target, mode, variant), members in groups.items():
        cells = []
        for mark in marks:
            at = [success_at(m.minutes, m.success, mark) for m in members]
            passing = sum(rate is not None and rate >= SUCCESS_SHARE - 1e-9 for rate in at)
            by = sum(
                m.passed_at is not None and m.passed_at <= mark + MARK_GRACE_MIN for m in members
            )
            cells += [f"{passing}/{len(members)}", f"{by}/{len(members)}"]
        lines.append(f"| {target} | {mode} | {variant} | {len(members)} | {' | '.join(cells)} |")
    return lines


def figure(runs: Sequence[TimedRun], path: Path, labels: Sequence[str] | None = None) -> Path:
    """Target score against the teacher's minutes, one panel per target, one line per run
    (colour: training mode, and variant when `labels` tell them apart), the success
    threshold dashed. Needs Matplotlib."""
    labels = ["as most"] * len(runs) if labels is None else labels
    curves = [
        Curve(
            r.target,
            r.threshold,
            r.mode if label == "as most" else f"{r.mode}, {label}",
            r.minutes,
            r.scores,
        )
        for r, label in zip(runs, labels, strict=True)
    ]
    return target_curves_figure(curves, path, "minutes of the teacher's time")


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0] if __doc__ else None)
    parser.add_argument("runs", nargs="*", type=Path, help="timed case-study directories")
    parser.add_argument(
        "--table",
        type=Path,
        help="also the runs of a tidy rounds table (CSV, one row per round: "
        + ", ".join(TABLE_COLUMNS)
        + ")",
    )
    parser.add_argument("--figure", type=Path, help="also draw the curves into this PNG")
    parser.add_argument(
        "--append-to",
        type=Path,
        metavar="CSV",
        help="append the rounds of the run directories given to this tidy rounds table "
        "(--table reads it back), named --variant",
    )
    parser.add_argument(
        "--variant", default="default", help="the name --append-to gives the runs' rows"
    )
    parser.add_argument(
        "--marks",
        type=float,
        nargs="+",
        help="minutes of the teacher's time: also a table of the runs passing at each",
    )
    args = parser.parse_args(argv)
    try:
        if args.append_to is not None:
            written = write_table(args.runs, args.variant, args.append_to)
            print(f"{written} rounds of {len(args.runs)} runs appended to {args.append_to}")
            return 0
        read = [read_run(run) for run in args.runs]
        read += [] if args.table is None else read_table(args.table)
    except (ValueError, OSError) as error:
        parser.error(str(error))
    if not read:
        parser.error("no runs: give run directories or --table")
    rows = sorted(
        zip(read, variants(read), strict=True),
        key=lambda row: (row[0].target, row[0].mode, row[1], row[0].seed),
    )
    runs = [run for run, _ in rows]
    labels = [
        run.config.get("variant", label) if len(run.config) == 1 else label for run, label in rows
    ]
    if args.figure:
        figure(runs, args.figure, labels)
    print("\n".join(summary_rows(runs, labels)))
    print()
    if args.marks:
        print("\n".join(mark_rows(runs, labels, args.marks)))
        print()
    print("\n".join(run_rows(runs, labels)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
