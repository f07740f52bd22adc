"""Issue 41's remedies on the case studies: the best recipe with each remedy (a partial
config), several seeds in parallel, with the learned reward's rank diagnostic per round.

    python research/walker_remedies.py OUT --seeds 0 1 2 3 4 --parallel 16
    python research/walker_remedies.py OUT --seeds 0 1 2 3 4 --parallel 16 \\
        --targets halfcheetah-standup hopper-backflip --setups baseline
    python research/walker_remedies.py OUT --table          # the table of what OUT holds

Every run is the best recipe of issue 20 (docs/results/case-studies/pretrain-variants/run.sh
through paper-pairs/run.sh): the Groupwise-DM, the teacher calibrated to people
(`--teacher-error 0.12`), the paper's preference pairs (`--pairs paper`, with 240, 260 and
380 comparisons for the splits, the stand-up and the backflip), 5 rounds of 40,000 PPO steps
with PPO's MuJoCo settings after 100,000 steps of state-entropy pre-training, 8 pool
variants; plus one setup of `SETUPS` as a partial config (`--config`, written to
OUT/configs/). Each run goes to OUT/<setup>/<target>-groupwise-s<seed> (no video); a run
whose summary.json exists is skipped, so an interrupted call resumes. Each process runs on
one core (OMP_NUM_THREADS=1; MUJOCO_GL as set, else egl). Then OUT/runs.csv is collected
(`results_table.py collect`) and a table printed: per setup and target, the seeds that
succeeded after the last round and as take-away agents (3 of 5 final greedy episodes at the
threshold), and the means over seeds of the last round's diagnostic (`reward_rank_rho`;
for the walker the learned reward per step on held-split steps, on the others, and on the
wide tilted stance).

Smaller budgets for a smoke run: --steps, --pretrain-steps, --rounds, --preferences.
"""

import argparse
import csv
import json
import math
import os
import shutil
import subprocess
import sys
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor, as_completed
from pathlib import Path
from typing import Any

SETUPS: dict[str, dict[str, Any]] = {
    "baseline": {},
    # the learned reward centred and scaled per step, no return scaling (imitation's
    # NormalizedRewardNet; issue 41, deliverable 3)
    "std-step": {"ppo": {"standardise_reward": True, "normalize_reward": False}},
}
"""Setup name -> the partial config it adds to the best recipe. Issue 41's remedies measured
no gain on the splits and left the code (docs/case-studies.md, "Measured and removed"):
PPE's coverage-mixed queries ("coverage"), PoLiCER's reward resets ("reset") and the
three combined ("all") are setups at commit 2710cd9, SURF's pseudo-labels with QPA's crops
("surf") at 5fed786. `--table` still reads their run folders."""
DEFAULT_SETUPS = ("baseline",)

COMPARISONS = {"walker-splits": 240, "halfcheetah-standup": 260, "hopper-backflip": 380}
"""The paper-pairs setup's comparisons per target (docs/results/case-studies/paper-pairs)."""
SEED_SUCCESS = 0.6
"""A seed succeeds when 3 of its 5 final greedy episodes reach the threshold."""
RANK_COLUMNS = ("reward_rank_rho", "reward_split", "reward_nonsplit", "reward_stance")


def check_dependencies(setups: Sequence[str]) -> str:
    """The `groupwise` command to run; exits with one line naming what is missing."""
    try:
        import mujoco  # noqa: F401

        from groupwise.config import RunConfig
        from groupwise.envs import make_env
        from groupwise.study.case_studies.case_record import CaseRecord
    except ImportError as error:
        sys.exit(f"walker_remedies: cannot import {error.name} (run with the project's venv)")
    if "reward_rank_rho" not in CaseRecord.__dataclass_fields__:
        sys.exit("walker_remedies: this groupwise has no reward_rank_rho (issue 41's code)")
    for name in setups:
        try:
            RunConfig().merged(SETUPS[name])
        except ValueError as error:
            sys.exit(f"walker_remedies: setup {name!r} is not a valid config here: {error}")
    try:
        make_env("Walker2d-splits").close()
    except Exception as error:  # MuJoCo's own errors are not one class
        sys.exit(f"walker_remedies: cannot make Walker2d-splits: {error}")
    command = Path(sys.executable).parent / "groupwise"
    found = str(command) if command.exists() else shutil.which("groupwise")
    if found is None:
        sys.exit("walker_remedies: no `groupwise` command beside this python or on PATH")
    return found


def run_command(
    groupwise: str, target: str, seed: int, config: Path, out: Path, args: argparse.Namespace
) -> list[str]:
    """The `groupwise case-study` command line of one run."""
    return [
        groupwise,
        "case-study",
        *("--target", target, "--dm", "groupwise"),
        *("--preferences", str(args.preferences or COMPARISONS[target]), "--pairs", "paper"),
        *("--rounds", str(args.rounds), "--steps", str(args.steps)),
        *("--teacher-error", "0.12", "--ppo", "mujoco", "--seed", str(seed)),
        *("--pretrain-steps", str(args.pretrain_steps), "--pool-variants", "8"),
        *("--config", str(config), "--out", str(out), "--no-video", "-q"),
    ]


def run_one(command: list[str], out: Path) -> str:
    """Run one case study into `out` (skipped when finished); a line saying how it ended."""
    if (out / "summary.json").is_file():
        return f"done before {out}"
    if out.exists():
        shutil.rmtree(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    env.setdefault("MUJOCO_GL", "egl")
    log = out.with_name(out.name + ".log")
    with log.open("w") as handle:
        code = subprocess.run(command, stdout=handle, stderr=subprocess.STDOUT, env=env).returncode
    return f"done {out}" if code == 0 else f"FAILED {out} (exit {code}, {log})"


def _last_row(run: Path) -> dict[str, str]:
    with (run / "case-study.csv").open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    return rows[-1] if rows else {}


def _mean(values: Sequence[float]) -> str:
    finite = [v for v in values if math.isfinite(v)]
    return f"{sum(finite) / len(finite):.3f}" if finite else "–"


def table(out: Path) -> list[str]:
    """One Markdown row per setup and target of the finished runs under `out`."""
    lines = [
        "| setup | target | seeds | successful, last round | take-away | mean ρ, last round "
        "| reward: split / not / stance |",
        "|---|---|---|---:|---:|---:|---|",
    ]
    for setup in sorted(p for p in out.iterdir() if p.is_dir() and p.name != "configs"):
        for target in COMPARISONS:
            runs = sorted(setup.glob(f"{target}-groupwise-s*/summary.json"))
            if not runs:
                continue
            summaries = [json.loads(r.read_text()) for r in runs]
            last = [_last_row(r.parent) for r in runs]
            seeds = ",".join(r.parent.name.rsplit("-s", 1)[1] for r in runs)
            final = sum(s["final"]["success_rate"] >= SEED_SUCCESS for s in summaries)
            away = sum(s["takeaway"]["success_rate"] >= SEED_SUCCESS for s in summaries)
            means = [_mean([float(r.get(c, "nan")) for r in last]) for c in RANK_COLUMNS]
            lines.append(
                f"| {setup.name} | {target} | {seeds} | {final}/{len(runs)} | {away}/{len(runs)} "
                f"| {means[0]} | {' / '.join(means[1:])} |"
            )
    return lines


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out", type=Path, help="where the setups' run folders go")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument("--parallel", type=int, default=os.cpu_count() or 1, help="processes")
    parser.add_argument("--setups", nargs="+", default=list(DEFAULT_SETUPS), choices=SETUPS)
    parser.add_argument("--targets", nargs="+", default=["walker-splits"], choices=COMPARISONS)
    parser.add_argument("--steps", type=int, default=40_000, help="PPO steps a round")
    parser.add_argument("--pretrain-steps", type=int, default=100_000)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--preferences", type=int, help="comparisons (default: the paper's)")
    parser.add_argument("--table", action="store_true", help="only print the table of OUT")
    args = parser.parse_args(argv)
    if args.table:
        print("\n".join(table(args.out)))
        return 0
    if args.parallel < 1:
        parser.error("--parallel must be >= 1")
    groupwise = check_dependencies(args.setups)
    configs = args.out / "configs"
    configs.mkdir(parents=True, exist_ok=True)
    jobs = []
    for setup in args.setups:
        config = configs / f"{setup}.json"
        config.write_text(json.dumps(SETUPS[setup], indent=2) + "\n")
        for seed in args.seeds:
            for target in args.targets:
                out = args.out / setup / f"{target}-groupwise-s{seed}"
                jobs.append((run_command(groupwise, target, seed, config, out, args), out))
    print(f"{len(jobs)} runs, {args.parallel} at a time, into {args.out}", flush=True)
    lines = []
    with ThreadPoolExecutor(args.parallel) as pool:  # the threads only wait on processes
        for job in as_completed([pool.submit(run_one, command, out) for command, out in jobs]):
            lines.append(job.result())
            print(lines[-1], flush=True)
    collect = Path(__file__).with_name("results_table.py")
    subprocess.run([sys.executable, str(collect), "collect", str(args.out)], check=False)
    print("\n".join(table(args.out)))
    return 1 if any(line.startswith("FAILED") for line in lines) else 0


if __name__ == "__main__":
    raise SystemExit(main())
