"""Issue 42's DMC table: the study's `dmc` profile and PPO on the true reward beside it.

    python research/dmc_study.py OUT [--seeds 2] [--workers 2]  # run what is missing, collect
    python research/dmc_study.py --table docs/results/dmc/runs.csv      # print the table
    python research/dmc_study.py --check docs/results/dmc/README.md     # `make lint` runs this

Runs `groupwise study --profile dmc --ablation noiseless` into OUT (Walker-walk and
Cheetah-run, the three DMs, 100 preferences: 100 comparisons, each DM held to one pair per
comparison; with SPEC §7's noisy teacher, and with a teacher that is never wrong, as the
published tables' scripted teacher), then, for each env and seed, PPO on the env's own
reward with the same PPO settings, steps and greedy evaluation
(`groupwise.study.simulation.reference`) into OUT/reference/ENV/seed-K/. Both skip what is
finished, so an interrupted call resumes. Then it collects OUT/runs.csv, one tidy row per
round (a cell) or evaluation (a reference), draws OUT/curves.png and prints the table: the
final greedy true return per env, teacher and DM (mean ± sd over seeds) beside the
reference and the published SAC-based numbers at 100 preferences. `--check README` renders
the table between the README's `<!-- dmc-table -->` markers from the runs.csv beside it and
exits 1 when it differs.
"""

import argparse
import csv
import os
import re
import shutil
import statistics
import subprocess
import sys
from collections import defaultdict
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

PUBLISHED_WALKER_WALK = {"PEBBLE": 453, "SURF": 661, "RUNE": 415, "QPA": 796, "PPE": 908}
"""Walker-walk at 100 preferences as PPE (NeurIPS 2025) reports it: SAC-based methods with a
scripted teacher, at their own step budgets (not ours)."""
ENVS = ("dm_control/walker-walk-v0", "dm_control/cheetah-run-v0")
DMS = ("pairwise", "groupwise", "interactive")
REFERENCE = "PPO, true reward"
CONDITIONS = {"cells": "SPEC §7 (σ 0.25 a step)", "noiseless": "never wrong"}
"""The study's directory of each teacher → how the table names it."""
COLOURS = {"pairwise": "C2", "groupwise": "C0", "interactive": "C1", REFERENCE: "black"}
COLUMNS = ("env", "teacher", "learner", "seed", "env_steps", "true_return_mean", "pairs_total")
EVERY = 50_000
"""PPO steps between the reference's evaluations."""
MARKER = re.compile(r"(<!-- dmc-table -->\n).*?(<!-- /dmc-table -->)", re.S)


def _env_directory(env: str) -> str:
    from groupwise.study.simulation.cells import env_directory

    return env_directory(env)


def reference_dir(out: Path, env: str, seed: int) -> Path:
    return out / "reference" / _env_directory(env) / f"seed-{seed}"


def run_reference(out: Path, env: str, seed: int) -> str:
    """PPO on `env`'s reward for a `dmc` cell's budget (skipped when its file exists)."""
    from groupwise.study.simulation.profiles import DMC
    from groupwise.study.simulation.reference import (
        REFERENCE_FILE,
        train_on_true_reward,
        write_points,
    )

    path = reference_dir(out, env, seed) / REFERENCE_FILE
    if path.is_file():
        return f"done before {path}"
    config = DMC.run_config(env, "pairwise", seed)
    write_points(train_on_true_reward(config, EVERY), path)
    return f"done {path}"


def _read(path: Path) -> list[dict[str, str]]:
    if not path.is_file():
        return []
    with path.open(newline="") as handle:
        return list(csv.DictReader(handle))


def collect(out: Path, seeds: int) -> list[dict[str, str]]:
    """One tidy row per round of every finished cell and per evaluation of every reference."""
    rows = []
    for env in ENVS:
        for seed in range(seeds):
            for condition, teacher in CONDITIONS.items():
                for dm in DMS:
                    cell = out / condition / _env_directory(env) / dm / f"seed-{seed}"
                    if (cell / "done.json").is_file():
                        rows += [
                            {"env": env, "teacher": teacher, "learner": dm, "seed": str(seed)}
                            | {k: r[k] for k in COLUMNS[4:]}
                            for r in _read(cell / "rounds.csv")
                        ]
            for r in _read(reference_dir(out, env, seed) / "reference.csv"):
                rows.append(
                    {"env": env, "teacher": "–", "learner": REFERENCE, "seed": str(seed)}
                    | {"env_steps": r["steps"], "true_return_mean": r["true_return_mean"]}
                    | {"pairs_total": "0"}
                )
    return rows


def write_rows(rows: Sequence[dict[str, str]], path: Path) -> None:
    with path.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)


def _finals(rows: Sequence[dict[str, str]]) -> dict[tuple[str, str, str], list[float]]:
    """(env, teacher, learner) → the final true return of each seed."""
    last: dict[tuple[str, str, str, str], dict[str, str]] = {}
    for r in rows:  # rows are in step order within a run
        last[(r["env"], r["teacher"], r["learner"], r["seed"])] = r
    finals: dict[tuple[str, str, str], list[float]] = defaultdict(list)
    for (env, teacher, learner, _), r in sorted(last.items()):
        finals[(env, teacher, learner)].append(float(r["true_return_mean"]))
    return finals


def _cell(values: Sequence[float]) -> str:
    if not values:
        return "–"
    sd = statistics.stdev(values) if len(values) > 1 else 0.0
    return f"{statistics.mean(values):.0f} ± {sd:.0f}"


def table(rows: Sequence[dict[str, str]]) -> list[str]:
    """The Markdown table: the final greedy true return, mean ± sd over seeds."""
    finals = _finals(rows)
    columns = [*DMS, REFERENCE]
    lines = [
        "| env | teacher | seeds | "
        + " | ".join(columns)
        + " | published at 100 preferences (SAC) |",
        "|---|---|---:|" + "---:|" * len(columns) + "---|",
    ]
    for env in ENVS:
        reference = _cell(finals.get((env, "–", REFERENCE), []))
        published = ", ".join(f"{k} {v}" for k, v in PUBLISHED_WALKER_WALK.items())
        for teacher in CONDITIONS.values():
            found = [finals.get((env, teacher, dm), []) for dm in DMS]
            seeds = max((len(f) for f in found), default=0)
            cells = [_cell(f) for f in found]
            lines.append(
                f"| {env.removeprefix('dm_control/')} | {teacher} | {seeds} | "
                + " | ".join([*cells, reference])
                + f" | {published if 'walker' in env else '–'} |"
            )
    return lines


def figure(rows: Sequence[dict[str, str]], path: Path) -> Path:
    """True return against PPO steps, mean over seeds: a panel per env, a line per teacher
    and DM, the reference dashed."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    runs: dict[tuple[str, str, str], dict[int, list[float]]] = defaultdict(
        lambda: defaultdict(list)
    )
    for r in rows:
        step = int(r["env_steps"])
        runs[(r["env"], r["teacher"], r["learner"])][step].append(float(r["true_return_mean"]))
    fig = Figure(figsize=(10, 3.8), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, len(ENVS))
    for ax, env in zip(axes, ENVS, strict=True):
        for (run_env, teacher, learner), points in sorted(runs.items()):
            if run_env != env:
                continue
            steps = sorted(points)
            means = [statistics.mean(points[s]) for s in steps]
            label = learner if learner == REFERENCE else f"{learner}, {teacher}"
            style = "--" if learner == REFERENCE else ("-" if teacher.startswith("never") else ":")
            ax.plot(steps, means, style, marker=".", label=label, color=COLOURS[learner])
        ax.set_title(env.removeprefix("dm_control/"))
        ax.set_xlabel("PPO env steps")
        ax.set_ylabel("greedy true return (mean over seeds)")
    for ax in axes:
        if ax.lines:
            ax.legend(fontsize=7, loc="upper left")
    fig.savefig(path, dpi=120)
    return path


def check(readme: Path) -> int:
    """0 when the README's marked table is the one its runs.csv gives, else 1 (a diff)."""
    text = readme.read_text()
    rows = _read(readme.parent / "runs.csv")
    expected = MARKER.sub(lambda m: m[1] + "\n".join(table(rows)) + "\n" + m[2], text)
    if MARKER.search(text) is None:
        print(f"{readme}: no <!-- dmc-table --> marker")
        return 1
    if expected != text:
        print(f"{readme}: the table differs from runs.csv; run --table and paste it")
        return 1
    return 0


def run(out: Path, seeds: int, workers: int) -> None:
    """The study's cells, then the references (each skipped when finished)."""
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    command = Path(sys.executable).parent / "groupwise"
    groupwise = str(command) if command.exists() else shutil.which("groupwise")
    if groupwise is None:
        sys.exit("dmc_study: no `groupwise` command beside this python or on PATH")
    study = [groupwise, "study", "--profile", "dmc", "--out", str(out), "--seeds", str(seeds)]
    study += ["--ablation", *(c for c in CONDITIONS if c != "cells")]
    code = subprocess.run([*study, "--workers", str(workers), "-q"]).returncode
    if code != 0:
        sys.exit(f"dmc_study: the study exited {code}")
    jobs = [(env, seed) for env in ENVS for seed in range(seeds)]
    with ProcessPoolExecutor(workers) as pool:
        futures = [pool.submit(run_reference, out, env, seed) for env, seed in jobs]
        for future in futures:
            print(future.result(), flush=True)


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("out", type=Path, nargs="?", help="the study's directory")
    parser.add_argument("--seeds", type=int, default=2)
    parser.add_argument("--workers", type=int, default=2, help="processes at a time")
    parser.add_argument("--table", type=Path, metavar="CSV", help="print the table of a runs.csv")
    parser.add_argument("--check", type=Path, metavar="README", help="check a README's table")
    args = parser.parse_args(argv)
    if args.check is not None:
        sys.exit(check(args.check))
    if args.table is not None:
        print("\n".join(table(_read(args.table))))
        return
    if args.out is None:
        parser.error("give OUT, --table CSV or --check README")
    run(args.out, args.seeds, args.workers)
    rows = collect(args.out, args.seeds)
    write_rows(rows, args.out / "runs.csv")
    figure(rows, args.out / "curves.png")
    print("\n".join(table(rows)))


if __name__ == "__main__":
    main()
