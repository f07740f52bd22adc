"""Benchmark: a simulated person teaching through the app's own path (issue 39).

For each target and seed it starts a real `groupwise serve` (uvicorn, SQLite, the training
worker) with one session of the target env, and plays a person on it over HTTP: it shows
each round (`…/shown`), asks the page's next group suggestion (`…/next-suggestion`),
answers it with the case studies' calibrated teacher (the Groupwise-DM's teacher with the
paper's people's label error, 12 % by default, its σ set per pool), one comparison every
`--pace` seconds (default: the paper's pace for the target, `run.continuous.paper_pace`),
and lets the round close itself at its comparison budget (`--comparisons`; default: the
paper's pairs of the target in `ROUNDS` rounds, 44 to 76; the app's New-session default is
20) or ends it when the suggestions run out. The worker trains as it would for a person.

The teacher's time is the wall time since round 0 opened (answers and waits alike). At each
mark of `--minutes` the benchmark copies the session's run directory (its committed
checkpoints and the mid-round checkpoint the worker writes every 30 s); after the session it
loads each copy's policy and measures its greedy episodes' target score in the target env,
as the case studies do (`study.case_studies.target_evaluation.evaluate_target`). A seed
succeeds when its success rate reaches `SEED_SUCCESS`, as in the case studies' tables. Each
cell also records the same policy's success when it samples its actions (as in the PPO
rollouts a fresh pool is cut from) and, per round, each pool source's mean true step score
(`pool_score`): what the person was shown, beside what the person takes away.

The teacher reads the true step scores of a round's behaviours from the pool files the
worker published (a person sees them in the clips); everything else goes through HTTP.

    python -m benchmarks.app_teacher [--targets hopper-backflip ...] [--seeds 0 1 2]
                                     [--minutes 10 20] [--pace S] [--label-error 0.12]
                                     [--training continuous|rounds] [--research JSON]
                                     [--comparisons N] [--variant NAME]
                                     [--out DIR] [--log FILE]
    python -m benchmarks.app_teacher --figure curves.png OUT/*/cells.jsonl
    python -m benchmarks.app_teacher --summary OUT/*/cells.jsonl

Prints one row per target and seed: success after each mark, PPO steps, the pool's age
when judged (PPO steps between the policy that sampled the judged behaviours and the policy
at the moment of the judgement: median / max) and End round → next round open (median), and
appends each cell to OUT/cells.jsonl; `--figure` draws the success rate against the
teacher's minutes from such files, and `--summary` prints one row per target and training
mode (and `--research`, a partial run config given to the session as the New-session API's
`research`) over their seeds.
"""

import argparse
import dataclasses
import json
import math
import re
import shutil
import statistics
import sys
import tempfile
import textwrap
import time
import uuid
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import httpx
import numpy as np

from benchmarks.submit_latency import start_server
from groupwise.behaviour.pool import BehaviourPool
from groupwise.config import RunConfig, TeacherConfig
from groupwise.envs import TARGETS, make_env
from groupwise.episodes.ids import behaviour_id, behaviour_index
from groupwise.pool.files import load_pool
from groupwise.preferences.judgement import LEFT_BETTER, RIGHT_BETTER
from groupwise.query.strategies import Query
from groupwise.run.checkpoint import CHECKPOINTS, STATE_FILE
from groupwise.run.continuous import PAPER_CASES, paper_pace
from groupwise.run.run import CONFIG_FILE, Run
from groupwise.storage.sessions import round_directory, session_directory
from groupwise.study.case_studies.table import SEED_SUCCESS
from groupwise.study.case_studies.target_evaluation import evaluate_target
from groupwise.teachers import DECISION_MAKERS
from groupwise.teachers.calibration import PEOPLE_LABEL_ERROR
from groupwise.worker.job import PRETRAINED

ROUNDS = 5
"""Rounds of a session, as the case studies' (the person stops at the last mark first)."""
EPISODES = 5
"""Greedy episodes measuring a copy's target score."""


@dataclass
class Cell:
    """What one target and seed measured."""

    target: str
    seed: int
    marks: dict[float, Path] = field(default_factory=dict)
    """minute → the copy of the run directory taken then."""
    ppo_steps: dict[float, int] = field(default_factory=dict)
    success: dict[float, float] = field(default_factory=dict)
    """minute → the success rate of the copy's greedy episodes."""
    scores: dict[float, float] = field(default_factory=dict)
    """minute → the mean target score of the copy's greedy episodes (the target's unit)."""
    sampled_success: dict[float, float] = field(default_factory=dict)
    """minute → the success rate of the copy's policy acting as in PPO's rollouts (sampling
    its actions), the behaviour a fresh pool shows the person."""
    sampled_scores: dict[float, float] = field(default_factory=dict)
    pool_scores: list[dict[str, float]] = field(default_factory=list)
    """Per round, each source's mean true step score over its behaviours in the pool
    (`pool_score`): what the person was shown."""
    pool_ages: list[int] = field(default_factory=list)
    waits: list[float] = field(default_factory=list)
    judgements: int = 0


def teacher_of(dm: str, label_error: float):
    """The case studies' simulated teacher of decision-maker `dm`, calibrated to `label_error`."""
    cfg = RunConfig(teacher=TeacherConfig(label_error=label_error))
    return DECISION_MAKERS[dm](
        dataclasses.replace(cfg, loop=dataclasses.replace(cfg.loop, decision_maker=dm))
    )


def state_of(http: httpx.Client, session: str) -> dict:
    state = http.get(f"/api/sessions/{session}").json()
    if state.get("phase") == "failed":
        raise RuntimeError(f"session {session} failed: {state.get('error')}")
    return state


def wait_open(http: httpx.Client, session: str, round_index: int, until: float) -> bool:
    """Poll until round `round_index` is open; False when `until` (monotonic) comes first."""
    while time.monotonic() < until:
        state = state_of(http, session)
        if state["phase"] == "ready" and state["round"] == round_index:
            return True
        time.sleep(0.05)
    return False


def pool_age(http: httpx.Client, session: str) -> int | None:
    summary = http.get(f"/api/sessions/{session}/training").json().get("summary")
    return None if summary is None else int(summary["pool_age"])


def pool_score(pool: BehaviourPool) -> dict[str, float]:
    """Each source's mean true step score over its behaviours in `pool` (source "0" the
    round's policy, the others the pool's other sources; "all" where sources are unknown)."""
    means = np.array([f.true_rewards.mean() for f in pool.fragments])
    sources = pool.sources if pool.sources is not None else np.zeros(len(means), np.int64)
    return {
        ("all" if pool.sources is None else str(s)): float(means[sources == s].mean())
        for s in np.unique(sources)
    }


def teach(
    target: str,
    seed: int,
    marks: Sequence[float],
    args: argparse.Namespace,
    out: Path,
) -> Cell:
    """One session of `target` taught by the simulated person until the last mark."""
    env = TARGETS[target].env
    pairs, _ = PAPER_CASES[target]
    comparisons = args.comparisons or round(pairs / 2.71 / ROUNDS)  # the paper's pairs
    pace = args.pace or paper_pace(target, pairwise=False)
    # enough rounds that the session outlasts the last mark, ROUNDS at the least
    rounds = max(ROUNDS, math.ceil(max(marks) * 60 / (comparisons * pace)) + 1)
    settings = {
        "seed": seed,
        "training": args.training,
        "rounds": rounds,
        "comparisons_per_round": comparisons,
        "round_seconds": 0,
        "frame_size": 96,
    }
    if args.research:
        settings["research"] = args.research
    feedback = teacher_of("groupwise", args.label_error)
    rng = np.random.default_rng(seed)
    cell = Cell(target, seed)
    with tempfile.TemporaryDirectory() as tmp:
        data = Path(tmp) / "data"
        process, url, session = start_server(data, env, None, args.log, settings)
        try:
            with httpx.Client(base_url=url, timeout=120) as http:
                if not wait_open(http, session, 0, time.monotonic() + 1800):
                    raise TimeoutError("round 0 did not open in 30 min")
                start = time.monotonic()
                pending = sorted(marks)
                round_index = 0
                while pending:
                    http.post(f"/api/sessions/{session}/rounds/{round_index}/shown")
                    run_dir = data / round_directory(session, round_index)
                    pool = load_pool(run_dir, round_index)
                    cell.pool_scores.append(pool_score(pool))
                    closed = False
                    while not closed and pending:
                        reply = http.post(
                            f"/api/sessions/{session}/rounds/{round_index}/next-suggestion",
                            json={"exclude": []},
                        )
                        suggestion = reply.json().get("suggestion") if reply.is_success else None
                        if suggestion is None:
                            http.post(f"/api/sessions/{session}/end-round")
                            closed = True
                            break
                        query = Query(
                            tuple(behaviour_index(b) for b in suggestion["left"]),
                            tuple(behaviour_index(b) for b in suggestion["right"]),
                        )
                        time.sleep(pace)
                        answered = feedback.teacher.answer(pool, [query], rng)
                        label = "equal"
                        left, right = query.left, query.right
                        if answered:
                            j = answered[0]
                            left, right = j.left, j.right
                            label = {LEFT_BETTER: "left", RIGHT_BETTER: "right"}.get(
                                j.label, "equal"
                            )
                        age = pool_age(http, session)
                        if age is not None:
                            cell.pool_ages.append(age)
                        body = {
                            "client_id": str(uuid.uuid4()),
                            "round": round_index,
                            "left": [behaviour_id(i) for i in left],
                            "right": [behaviour_id(i) for i in right],
                            "label": label,
                            "source": "suggested",
                            "seconds": pace,
                        }
                        http.post(f"/api/sessions/{session}/judgements", json=body)
                        cell.judgements += 1
                        state = state_of(http, session)
                        closed = state["round"] != round_index or state["phase"] != "ready"
                        _take_marks(cell, pending, start, data, session, out)
                    if not pending:
                        break
                    tick = time.monotonic()
                    last = round_index + 1 >= rounds
                    if last or not wait_open(http, session, round_index + 1, tick + 1800):
                        break
                    cell.waits.append(time.monotonic() - tick)
                    round_index += 1
                while pending:  # the rounds ran out before the last mark: wait for it
                    time.sleep(1.0)
                    _take_marks(cell, pending, start, data, session, out)
        finally:
            process.terminate()
            process.wait(timeout=60)
    return cell


def _take_marks(
    cell: Cell, pending: list[float], start: float, data: Path, session: str, out: Path
) -> None:
    """Copy the run directory at each mark whose minute has come."""
    while pending and time.monotonic() - start >= 60 * pending[0]:
        minute = pending.pop(0)
        copy = out / f"{cell.target}-s{cell.seed}-m{minute:g}"
        shutil.rmtree(copy, ignore_errors=True)
        source = data / session_directory(session)
        shutil.copytree(source, copy, ignore=_pool_directories(source))
        cell.marks[minute] = copy


def _pool_directories(session: Path):
    """A `copytree` ignore: the session's round pools (its top-level round-NNNN folders,
    clips and all), not the committed checkpoints of the same name under checkpoints/."""
    pools = re.compile(r"round-\d{4}")

    def ignore(directory: str, names: list[str]) -> list[str]:
        if Path(directory) != session:
            return []
        return [name for name in names if pools.fullmatch(name)]

    return ignore


def evaluate_copy(cell: Cell, minute: float, copy: Path) -> None:
    """The success rate of the greedy policy in `copy` (the newest of its committed and
    mid-round checkpoints), measured on the target env; beside it, that of the same policy
    sampling its actions, as it does in the rollouts a fresh pool is cut from."""
    cfg = RunConfig.load(copy / CONFIG_FILE)
    with Run.create(cfg, copy) as run:
        committed = run.restore()
        if not run.restore_mid_round(run.next_round) and not committed:
            # round 0 open and no PPO since (rounds mode): the policy pre-training left
            pretrained = copy / CHECKPOINTS / PRETRAINED
            if (pretrained / STATE_FILE).is_file():
                run.load_policy(pretrained)
            elif cfg.training.pretrain_steps > 0:
                raise RuntimeError(f"{copy} holds no checkpoint to evaluate")
        cell.ppo_steps[minute] = int(run.agent.num_timesteps)
        target = TARGETS[cell.target]
        rng = np.random.default_rng([cell.seed, int(minute)])
        for deterministic, success, scores in (
            (True, cell.success, cell.scores),
            (False, cell.sampled_success, cell.sampled_scores),
        ):
            evaluation = evaluate_target(
                lambda: make_env(target.env), run.agent.policy(deterministic), EPISODES, rng
            )
            success[minute] = evaluation.success_rate(target)
            scores[minute] = float(evaluation.scores.mean())


def table(cells: Sequence[Cell], marks: Sequence[float]) -> str:
    head = ["target", "seed", *(f"success {m:g} min" for m in marks)]
    head += [*(f"PPO steps {m:g} min" for m in marks), "comparisons"]
    head += ["pool age, median / max", "End round → open, median (s)"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for cell in cells:
        ages = cell.pool_ages or [0]
        wait = f"{statistics.median(cell.waits):.2f}" if cell.waits else "–"
        row = [cell.target, str(cell.seed)]
        row += [_success(cell, m) for m in marks]
        row += [f"{cell.ppo_steps.get(m, 0):,}" for m in marks]
        row += [str(cell.judgements), f"{statistics.median(ages):,.0f} / {max(ages):,}", wait]
        lines.append("| " + " | ".join(row) + " |")
    for target in dict.fromkeys(c.target for c in cells):
        of = [c for c in cells if c.target == target]
        counts = ", ".join(
            f"{sum(c.success.get(m, 0.0) >= SEED_SUCCESS for c in of)}/{len(of)} at {m:g} min"
            for m in marks
        )
        lines.append(f"\n{target}: successful seeds {counts}")
    return "\n".join(lines)


def cell_record(
    cell: Cell,
    training: str,
    research: dict | None = None,
    comparisons: int | None = None,
    variant: str | None = None,
) -> dict:
    """One cell as a JSON line (`--figure` reads them back); `comparisons` is a round's
    budget where `--comparisons` set it (None: the paper's pairs in `ROUNDS` rounds);
    `variant` names the code the cell ran where `--variant` did (an earlier default)."""
    return {
        "target": cell.target,
        "seed": cell.seed,
        "training": training,
        "variant": variant,
        "research": research,
        "comparisons_per_round": comparisons,
        "success": {f"{m:g}": rate for m, rate in cell.success.items()},
        "scores": {f"{m:g}": score for m, score in cell.scores.items()},
        "sampled_success": {f"{m:g}": rate for m, rate in cell.sampled_success.items()},
        "sampled_scores": {f"{m:g}": score for m, score in cell.sampled_scores.items()},
        "pool_scores": cell.pool_scores,
        "ppo_steps": {f"{m:g}": steps for m, steps in cell.ppo_steps.items()},
        "comparisons": cell.judgements,
        "pool_ages": cell.pool_ages,
        "waits": cell.waits,
    }


def figure(records: Sequence[dict], path: Path) -> None:
    """Success rate against the teacher's minutes, a panel per target, a line per arm
    (`arm`: training mode, research settings, round budget) and seed (thin) with the arms'
    means (thick)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    targets = list(dict.fromkeys(r["target"] for r in records))
    fig, axes = plt.subplots(
        len(targets), 1, figsize=(12.0, 3.4 * len(targets)), squeeze=False
    )  # one panel a row: the arms' names are long, their legend (wrapped) sits beside it
    fig.subplots_adjust(left=0.07, right=0.5, hspace=0.45)
    arms = sorted({arm(r) for r in records})
    colours = dict(zip(arms, plt.get_cmap("tab10").colors, strict=False))
    for ax, target in zip(axes[:, 0], targets, strict=True):
        for training, colour in colours.items():
            runs = [r for r in records if r["target"] == target and arm(r) == training]
            if not runs:
                continue
            minutes = sorted({float(m) for r in runs for m in r["success"]})
            rates = np.array([[r["success"].get(f"{m:g}", np.nan) for m in minutes] for r in runs])
            for row in rates:
                ax.plot(minutes, row, color=colour, alpha=0.3, lw=1)
            label = f"{training} ({len(runs)} seed{'' if len(runs) == 1 else 's'})"
            label = textwrap.fill(label, 70, subsequent_indent="  ")
            ax.plot(minutes, np.nanmean(rates, axis=0), color=colour, lw=2.5, label=label)
        ax.axhline(SEED_SUCCESS, color="grey", ls=":", lw=1)
        ax.set_ylim(-0.05, 1.05)
        ax.set_title(target)
        ax.set_xlabel("teacher's minutes")
        ax.set_ylabel("greedy episodes succeeding")
        ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.02, 0.5), frameon=False)
    fig.savefig(path, dpi=110, bbox_inches="tight")


def arm(record: dict) -> str:
    """A cell's training mode, with its variant, research settings and its rounds'
    comparison budget when it had them."""
    research, budget = record.get("research"), record.get("comparisons_per_round")
    variant = record.get("variant")
    return (
        record["training"]
        + (f" [{variant}]" if variant else "")
        + (f" {json.dumps(research)}" if research else "")
        + (f", {budget} comparisons a round" if budget else "")
    )


def summary(records: Sequence[dict]) -> str:
    """Two tables over the seeds of `records` (`cell_record`s), as docs/results/continuous
    shows them: per target and training mode, the seeds that passed at each mark, the mean
    success rate and each seed's mean target score at the last, the median PPO steps there
    and comparisons, the pooled pool ages (median / max) and End round waits (median,
    range); then each seed's success rate at each mark."""
    marks = sorted({float(m) for r in records for m in r["success"]}, key=float)
    keys = [f"{m:g}" for m in marks]
    seeds = sorted({r["seed"] for r in records})
    groups = sorted({(r["target"], arm(r)) for r in records})
    cells = {(t, mode): sorted((r for r in records if (r["target"], arm(r)) == (t, mode)),
                               key=lambda r: r["seed"]) for t, mode in groups}  # fmt: skip
    at = " / ".join(keys)
    lines = [
        f"| target | training | passed at {at} min (seeds) | mean success at {keys[-1]} min "
        f"| target score at {keys[-1]} min, per seed "
        f"| PPO steps at {keys[-1]} min, median | comparisons | pool age when judged, median / "
        "max (PPO steps) | End round → next round open, median (range) |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for (target, training), of in cells.items():
        passed = " / ".join(
            str(sum(r["success"].get(k, 0.0) >= SEED_SUCCESS for r in of)) for k in keys
        )
        mean = statistics.fmean(r["success"].get(keys[-1], 0.0) for r in of)
        scores = ", ".join(
            f"{r['scores'][keys[-1]]:.2f}" if keys[-1] in r.get("scores", {}) else "–" for r in of
        )
        steps = statistics.median(r["ppo_steps"].get(keys[-1], 0) for r in of)
        judged = statistics.median(r["comparisons"] for r in of)
        ages = [a for r in of for a in r.get("pool_ages", [])]
        waits = [w for r in of for w in r.get("waits", [])]
        age = f"{statistics.median(ages):,.0f} / {max(ages):,}" if ages else "–"
        wait = (
            f"{statistics.median(waits):.2f} s ({min(waits):.1f}–{max(waits):.1f})"
            if waits
            else "–"
        )
        lines.append(
            f"| {target} | {training} | {passed} (of {len(of)}) | {mean:.0%} | {scores} "
            f"| {steps:,.0f} | {judged:g} | {age} | {wait} |"
        )
    lines += ["", f"Per seed, success at {at} min (share of {EPISODES} greedy episodes):", ""]
    lines.append("| target | training | " + " | ".join(f"seed {s}" for s in seeds) + " |")
    lines.append("|---|---|" + "---|" * len(seeds))
    for (target, training), of in cells.items():
        by_seed = {r["seed"]: r["success"] for r in of}
        row = [
            " / ".join(f"{100 * by_seed[s].get(k, 0.0):.0f}" for k in keys) + " %"
            if s in by_seed
            else "–"
            for s in seeds
        ]
        lines.append(f"| {target} | {training} | " + " | ".join(row) + " |")
    return "\n".join(lines)


def _success(cell: Cell, minute: float) -> str:
    rate = cell.success.get(minute)
    if rate is None:
        return "–"
    return f"{'yes' if rate >= SEED_SUCCESS else 'no'} ({rate:.0%})"


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--targets", nargs="+", default=list(PAPER_CASES), choices=TARGETS)
    parser.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    parser.add_argument("--minutes", nargs="+", type=float, default=[10.0, 20.0])
    parser.add_argument("--pace", type=float, help="seconds per comparison (the paper's)")
    parser.add_argument("--label-error", type=float, default=PEOPLE_LABEL_ERROR)
    parser.add_argument(
        "--comparisons",
        type=int,
        help=f"a round's comparison budget (default: the paper's pairs in {ROUNDS} rounds; "
        "the app's New-session default is 20)",
    )
    parser.add_argument("--training", choices=("continuous", "rounds"), default="continuous")
    parser.add_argument(
        "--research",
        type=json.loads,
        help='a partial run config for the sessions, e.g. \'{"reward": {"use_actions": false}}\'',
    )
    parser.add_argument(
        "--variant", help="name the code the cells run in their records, e.g. an earlier default"
    )
    parser.add_argument("--out", type=Path, help="keep the copies here (default: a temp dir)")
    parser.add_argument("--log", type=Path, help="write the servers' and workers' logs here")
    parser.add_argument(
        "--figure",
        nargs="+",
        type=Path,
        metavar=("PNG", "JSONL"),
        help="only draw PNG from earlier runs' cells.jsonl files",
    )
    parser.add_argument(
        "--summary",
        nargs="+",
        type=Path,
        metavar="JSONL",
        help="only print the rows per target and training mode of earlier runs' cells.jsonl",
    )
    args = parser.parse_args([] if argv is None else list(argv))
    if args.summary:
        print(
            summary([json.loads(line) for f in args.summary for line in f.read_text().splitlines()])
        )
        return
    if args.figure:
        png, *files = args.figure
        figure([json.loads(line) for f in files for line in f.read_text().splitlines()], png)
        return
    cells: list[Cell] = []
    with tempfile.TemporaryDirectory() as tmp:
        out = args.out or Path(tmp)
        out.mkdir(parents=True, exist_ok=True)
        for target in args.targets:
            for seed in args.seeds:
                cell = teach(target, seed, args.minutes, args, out)
                for minute, copy in cell.marks.items():
                    evaluate_copy(cell, minute, copy)
                cells.append(cell)
                with (out / "cells.jsonl").open("a") as handle:
                    handle.write(
                        json.dumps(
                            cell_record(
                                cell, args.training, args.research, args.comparisons, args.variant
                            )
                        )
                        + "\n"
                    )
                print(
                    f"{time.strftime('%H:%M:%S')} {target} seed {seed}: greedy {cell.success}, "
                    f"sampled {cell.sampled_success}, pools {cell.pool_scores}",
                    file=sys.stderr,
                )
    print(
        f"The app's path: one session at a time, {args.training} training, the calibrated "
        f"teacher (label error {args.label_error:g}), {EPISODES} greedy episodes a mark\n"
    )
    print(table(cells, args.minutes))


if __name__ == "__main__":
    main(sys.argv[1:])
