"""Issue 42's DMC table: the study's `dmc` profile and PPO on the true reward beside it.

    python research/dmc_study.py OUT [--seeds 2] [--workers 2]  # what is missing, then the table
    python research/dmc_study.py OUT --table                     # the table of what OUT holds

Runs `groupwise study --profile dmc --ablation noiseless` into OUT (Walker-walk and
Cheetah-run, the three DMs, 100 preferences: 100 comparisons, each DM held to one pair per
comparison; with SPEC §7's noisy teacher, and with a teacher that is never wrong, as the
published tables' scripted teacher), then, for each
env and seed, PPO on the env's own reward with the same PPO settings, steps and greedy
evaluation (`groupwise.study.simulation.reference`) into OUT/reference/ENV/seed-K/. Both
skip what is finished, so an interrupted call resumes. Then prints one Markdown table: the
final greedy true return per env, teacher and DM (mean ± sd over seeds) beside the
reference and the published SAC-based numbers at 100 preferences.
"""

import argparse
import csv
import os
import shutil
import statistics
import subprocess
import sys
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from groupwise.study.simulation.cells import env_directory
from groupwise.study.simulation.profiles import DMC, PAPER_DMS
from groupwise.study.simulation.reference import (
    REFERENCE_FILE,
    train_on_true_reward,
    write_points,
)

PUBLISHED_WALKER_WALK = {"PEBBLE": 453, "SURF": 661, "RUNE": 415, "QPA": 796, "PPE": 908}
"""Walker-walk at 100 preferences as PPE (NeurIPS 2025) reports it, SAC-based methods after
500 k env steps (their own budgets, not ours)."""
CONDITIONS = {"cells": "SPEC §7 (σ 0.25 a step)", "noiseless": "never wrong"}
"""The study's directory of each teacher → how the table names it."""
EVERY = 50_000
"""PPO steps between the reference's evaluations."""


def reference_file(out: Path, env: str, seed: int) -> Path:
    return out / "reference" / env_directory(env) / f"seed-{seed}" / REFERENCE_FILE


def run_reference(out: Path, env: str, seed: int) -> str:
    """PPO on `env`'s reward for a `dmc` cell's budget (skipped when its file exists)."""
    path = reference_file(out, env, seed)
    if path.is_file():
        return f"done before {path}"
    config = DMC.run_config(env, "pairwise", seed)
    write_points(train_on_true_reward(config, EVERY), path)
    return f"done {path}"


def final_return(rounds_csv: Path) -> float | None:
    """The last row's greedy true return of a cell's rounds.csv (None: not there)."""
    if not rounds_csv.is_file():
        return None
    with rounds_csv.open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    return float(rows[-1]["true_return_mean"]) if rows else None


def _cell(values: Sequence[float]) -> str:
    if not values:
        return "–"
    sd = statistics.stdev(values) if len(values) > 1 else 0.0
    return f"{statistics.mean(values):.0f} ± {sd:.0f} (n={len(values)})"


def table(out: Path, seeds: int) -> list[str]:
    """The Markdown table of the finished cells and references under `out`."""
    columns = [*PAPER_DMS, "PPO, true reward"]
    lines = [
        "| env | teacher | "
        + " | ".join(columns)
        + " | published at 100 preferences (SAC, 500 k steps) |",
        "|---|---|" + "---:|" * len(columns) + "---|",
    ]
    for env in DMC.envs:
        references = [final_return(reference_file(out, env, s)) for s in range(seeds)]
        reference = _cell([v for v in references if v is not None])
        published = (
            ", ".join(f"{k} {v}" for k, v in PUBLISHED_WALKER_WALK.items())
            if env.startswith("dm_control/walker-walk")
            else "–"
        )
        for condition, teacher in CONDITIONS.items():
            cells = []
            for dm in PAPER_DMS:
                folder = out / condition / env_directory(env) / dm
                found = [final_return(folder / f"seed-{s}" / "rounds.csv") for s in range(seeds)]
                cells.append(_cell([v for v in found if v is not None]))
            lines.append(
                f"| {env} | {teacher} | " + " | ".join([*cells, reference]) + f" | {published} |"
            )
    return lines


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("out", type=Path)
    parser.add_argument("--seeds", type=int, default=DMC.seeds)
    parser.add_argument("--workers", type=int, default=2, help="processes at a time")
    parser.add_argument("--table", action="store_true", help="only print the table")
    args = parser.parse_args(argv)
    if not args.table:
        os.environ.setdefault("OMP_NUM_THREADS", "1")
        command = Path(sys.executable).parent / "groupwise"
        groupwise = str(command) if command.exists() else shutil.which("groupwise")
        if groupwise is None:
            sys.exit("dmc_study: no `groupwise` command beside this python or on PATH")
        study = [groupwise, "study", "--profile", "dmc", "--out", str(args.out)]
        study += ["--ablation", *(c for c in CONDITIONS if c != "cells")]
        study += ["--seeds", str(args.seeds), "--workers", str(args.workers), "-q"]
        code = subprocess.run(study).returncode
        if code != 0:
            sys.exit(f"dmc_study: the study exited {code}")
        jobs = [(env, seed) for env in DMC.envs for seed in range(args.seeds)]
        with ProcessPoolExecutor(args.workers) as pool:
            futures = [pool.submit(run_reference, args.out, env, seed) for env, seed in jobs]
            for future in futures:
                print(future.result(), flush=True)
    print("\n".join(table(args.out, args.seeds)))


if __name__ == "__main__":
    main()
