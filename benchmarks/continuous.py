"""Benchmark: continuous training in the app (issue 24), against PPO's one-core throughput.

Starts a real server (`groupwise serve`: uvicorn, SQLite, the training worker process) with
one session of `--env` whose settings say ``training: "continuous"``, and plays a person:
one comparison every `--pace` seconds for `--minutes` minutes a round, then "End round",
for `--rounds` rounds (or: `--budget` comparisons end a round, or `--round-seconds` of its
timer do). Meanwhile it reads the worker's mid-round checkpoint
(``checkpoints/live/state.json``: PPO steps, written every 30 s) to measure PPO steps per
minute of session time, and times each judgement's answer and each wait from "End round"
until the next round is open (the person's wait: the worker cuts the next pool from PPO's
latest rollouts when the round ends, issue 39). It reports the opened pools' ages (PPO
steps from the policy that played each behaviour to the policy when the round opened, from
each ``pool.json``), beside the ages the earlier stage-ahead design gave (a pool sampled
from a snapshot `--stage-after` seconds into the round before, read off the session's
learning-curve points). It measures PPO's single-core throughput the same way as
`ppo_throughput` (CPU time, learned reward) and prints a Markdown table.

    python -m benchmarks.continuous [--env Hopper] [--rounds 10] [--minutes 1.5] [--pace 5]
                                    [--budget N | --round-seconds S]
                                    [--recipe teach] [--pretrain-steps 0] [--frame-size 240]
                                    [--research JSON] [--stage-after 60] [--log FILE]

The End-round table splits the wait as the worker measured it in each round's
``opening.json`` (`worker.jobs.OpeningClock`, issue 39): the PPO slice in progress, the last
fit, sampling, DTW + tree + queries, clips and posters, the database write.

Measured on this 2-core machine, Hopper, defaults (`--rounds 10 --minutes 1.5`): End round →
next round open, median / p95 (max); PPO steps per minute of session time against one core's
per CPU-minute; judgement answers, median / p99.

- next round sampled on PPO's thread (load 1.6): 1.0 / 3.2 s (3.8); 0.75×; 19 / 919 ms;
- the stager process (load 1.3): 0.1 / 0.3 s (0.5); 0.73×; 16 / 498 ms;
- and the curve's evaluations in a process of their own, no second fit of the same pairs
  when a round is committed, the background processes at niceness +5 (load 1.2):
  0.1 / 0.1 s (0.1); **0.81×** (81,148 vs 99,932); 16 / 517 ms.

With fresh pools (issue 39: the next pool at most one rollout old, sampled when the round
ends), the app's defaults (`teach`, 240 px), 10 rounds of 45 s (load 6–7): 11.4 / 12.4 s
before, **7.6 / 9.2 s** once the slice in progress stops at End round and the pool variants
are sampled side by side; 5.9 s of it sampling (docs/results/continuous/README.md). With
`--budget 9` (the round's budget ends it, 9 comparisons at 5 s; load 1.0) the worker cuts
the next pool 2-3 comparisons before the end and PPO waits: **0.21 / 4.0 s**, PPO at 0.62×.
With `--round-seconds 45` (the round's timer ends it; the page shows each round as it
opens) the worker cuts a cut's length before the timer's end: **0.27 / 2.1 s** (max 3.0, a
cut 2.7 s longer than the one before), PPO at 0.58× (load 1.1).

The worker logs where its time goes every minute (`worker.continuous`, "the last 61 s: PPO 59.6 s
(98%), refits 1.1 s (2%), ..."); before the evaluations moved out they took 9–10 % of it.
"""

import argparse
import json
import os
import statistics
import sys
import tempfile
import threading
import time
import uuid
from collections.abc import Sequence
from pathlib import Path

import httpx
import numpy as np
import torch

from benchmarks.ppo_throughput import steps_per_second
from benchmarks.submit_latency import start_server, wait_for
from groupwise.config import RunConfig
from groupwise.pool.files import load_sources
from groupwise.pool.recent import kept_tag
from groupwise.run.run import CONFIG_FILE
from groupwise.storage.sessions import round_directory
from groupwise.worker.jobs import OPENING_FILE

SETTINGS = {
    "pool_size": 100,
    "round_seconds": 0,
    "comparisons_per_round": 0,
    "rounds": 3,  # set to --rounds + 1
    "training": "continuous",
}
PARTS = {
    "before": "the slice in progress (PPO) and picking the job up",
    "refit": "the last fit brought up to date",
    "sample": "sampling what the latest rollout lacks",
    "cut": "DTW, tree and queries",
    "publish": "clips, posters and pool files",
    "store": "the database write that opens it",
    "other": "the rest of the job",
}
"""The parts of the wait from End round to the next round's opening, as the worker writes
them to each round's ``opening.json`` (`worker.jobs.OpeningClock`)."""


def _mid_round_steps(data: Path, session: str) -> int | None:
    state = data / "sessions" / session / "checkpoints" / "live" / "state.json"
    try:
        return int(json.loads(state.read_text())["env_steps"])
    except (OSError, ValueError, KeyError):
        return None


def _wait_open(http: httpx.Client, session: str, round_index: int) -> None:
    """Poll (every 50 ms) until round `round_index` is open."""
    deadline = time.monotonic() + 900
    while time.monotonic() < deadline:
        state = http.get(f"/api/sessions/{session}").json()
        if state["phase"] == "failed":
            raise RuntimeError(f"session {session} failed: {state['error']}")
        if state["phase"] == "ready" and state["round"] == round_index:
            return
        time.sleep(0.05)
    raise TimeoutError(f"round {round_index} of {session} did not open")


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--env", default="Hopper")
    parser.add_argument("--rounds", type=int, default=10, help="rounds ended")
    parser.add_argument("--minutes", type=float, default=1.5, help="minutes a round")
    parser.add_argument("--pace", type=float, default=5.0, help="seconds per comparison")
    parser.add_argument(
        "--stage-after",
        type=float,
        default=60.0,
        help="for the comparison only: seconds into a round when the earlier design sampled "
        "the next pool (the app's stage_after_s was 60)",
    )
    parser.add_argument(
        "--recipe", default="teach", help="the session's recipe (the app's default: teach)"
    )
    parser.add_argument(
        "--pretrain-steps",
        type=int,
        default=0,
        help="pre-training before round 0 (the recipe's on MuJoCo is 100,000; it changes the "
        "policy round 0 starts from, not the work at End round)",
    )
    parser.add_argument(
        "--frame-size", type=int, default=240, help="clip pixels (the app's default: 240)"
    )
    parser.add_argument(
        "--research",
        type=json.loads,
        default=None,
        help='a partial run config for the session\'s "research" setting, as JSON (e.g. '
        '\'{"loop": {"pool_oversample": 1}}\')',
    )
    parser.add_argument(
        "--budget",
        type=int,
        default=0,
        help="comparisons a round: the person's last one ends it at its budget, and the "
        "worker cuts the next pool during it (default 0: End round after --minutes)",
    )
    parser.add_argument(
        "--round-seconds",
        type=float,
        default=0.0,
        help="the round's timer: the page shows each round as it opens, the person answers "
        "until the timer ends the round, and the worker cuts the next pool that many seconds "
        "before (default 0: End round after --minutes)",
    )
    parser.add_argument("--log", type=Path, help="write the server's and worker's log here")
    args = parser.parse_args([] if argv is None else list(argv))
    rng = np.random.default_rng(0)
    latencies: list[float] = []
    samples: list[tuple[float, int]] = []
    waits: list[float] = []
    ended: list[float] = []  # wall clock of each End round
    opened: list[float] = [time.time()]  # of each round's opening (round 0: the start)
    points: list[dict] = []
    with tempfile.TemporaryDirectory() as tmp:
        data = Path(tmp) / "data"
        process, url, first = start_server(data, args.env, None, args.log)
        try:
            with httpx.Client(base_url=url, timeout=60) as http:
                wait_for(http, first, "ready")  # the server is up (its CLI session ready)
                settings = {
                    **SETTINGS,
                    "rounds": args.rounds + 1,
                    "comparisons_per_round": args.budget,
                    "round_seconds": args.round_seconds,
                    "recipe": args.recipe,
                    "pretrain_steps": args.pretrain_steps,
                    "frame_size": args.frame_size,
                    **({} if args.research is None else {"research": args.research}),
                }
                session = http.post(
                    "/api/sessions", json={"env": args.env, "settings": settings}
                ).json()["id"]
                wait_for(http, session, "ready")
                opened[0] = time.time()
                pool = SETTINGS["pool_size"]
                done = threading.Event()

                def watch() -> None:
                    while not done.wait(1.0):
                        steps = _mid_round_steps(data, session)
                        if steps is not None and (not samples or samples[-1][1] != steps):
                            samples.append((time.monotonic(), steps))

                watcher = threading.Thread(target=watch, daemon=True)
                watcher.start()
                for round_index in range(args.rounds):
                    end = time.monotonic() + 60 * args.minutes
                    if args.round_seconds:  # a page shows the round: its timer starts
                        http.post(f"/api/sessions/{session}/rounds/{round_index}/shown")
                        end = time.monotonic() + args.round_seconds - args.pace
                    given = 0
                    while time.monotonic() < end if not args.budget else given < args.budget:
                        a, b, c = (f"b{i}" for i in rng.choice(pool, size=3, replace=False))
                        body = {
                            "client_id": str(uuid.uuid4()),
                            "round": round_index,
                            "left": [a, b],
                            "right": [c],
                            "label": "left",
                            "source": "explored",
                        }
                        if args.budget:  # compare, then answer; the last answer ends
                            time.sleep(args.pace)  # the round at its budget: the wait begins
                            if given == args.budget - 1:
                                ended.append(time.time())
                        tick = time.perf_counter()
                        answer = http.post(f"/api/sessions/{session}/judgements", json=body)
                        latencies.append(time.perf_counter() - tick)
                        answer.raise_for_status()
                        given += 1
                        if not args.budget:
                            time.sleep(args.pace)
                    if args.round_seconds:  # the timer ends the round
                        time.sleep(max(0.0, end + args.pace - time.monotonic()))
                        tick = time.perf_counter()
                        ended.append(time.time())
                    elif not args.budget:
                        tick = time.perf_counter()
                        ended.append(time.time())
                        http.post(f"/api/sessions/{session}/end-round").raise_for_status()
                    _wait_open(http, session, round_index + 1)
                    waits.append(time.perf_counter() - tick)
                    opened.append(time.time())
                    print(
                        f"{time.strftime('%H:%M:%S')} round {round_index + 1} open "
                        f"{waits[-1]:.2f} s after End round",
                        file=sys.stderr,
                    )
                done.set()
                watcher.join()
                points = http.get(f"/api/sessions/{session}/training").json()["points"]
            ages = [_pool_ages(data, session, r) for r in range(1, args.rounds + 1)]
            openings = [_opening(data, session, r) for r in range(1, args.rounds + 1)]
        finally:
            process.terminate()
            process.wait(timeout=30)
    before = _stage_ahead_ages(points, opened, ended, args.stage_after)
    torch.set_num_threads(1)
    single = steps_per_second(args.env, learned=True)
    if len(samples) >= 2:
        (t0, s0), (t1, s1) = samples[0], samples[-1]
        per_minute = (s1 - s0) / (t1 - t0) * 60
    else:
        per_minute = float("nan")
    research = "" if args.research is None else f", research {json.dumps(args.research)}"
    print(
        f"{args.env}, one continuous session (recipe {args.recipe}, pre-training "
        f"{args.pretrain_steps:,} steps, {args.frame_size} px clips{research}), a comparison "
        f"every {args.pace:g} s, "
        + (
            f"{args.budget} a round (its budget ends it), next pool cut from the latest "
            "rollouts during the last"
            if args.budget
            else f"for {args.round_seconds:g} s a round (its timer ends it), next pool cut "
            "from the latest rollouts before"
            if args.round_seconds
            else f"for {args.minutes:g} min a round, next pool cut from the latest rollouts "
            "at its end"
        )
        + f", {args.rounds} rounds, {os.cpu_count()} CPUs, "
        f"load average {os.getloadavg()[0]:.1f}\n"
    )
    _print_waits(waits, openings)
    print("| measure | value |")
    print("|---|---:|")
    print(f"| PPO steps per minute of session time (mid-round checkpoints) | {per_minute:,.0f} |")
    print(f"| PPO one core, learned reward (steps per minute of CPU time) | {single * 60:,.0f} |")
    print(f"| ratio | {per_minute / (single * 60):.2f} |")
    p50, p99 = np.percentile(latencies, [50, 99]) * 1000
    print(f"| judgement answer, median / p99 (ms, n={len(latencies)}) | {p50:.0f} / {p99:.0f} |")
    w50, w95 = np.percentile(waits, [50, 95])
    print(
        f"| End round → next round open, median / p95 (s, n={len(waits)}) | {w50:.1f} / {w95:.1f} |"
    )
    print(f"| End round → next round open, max (s) | {max(waits):.1f} |")
    fresh = np.concatenate([a for a, _ in ages])
    kept = np.concatenate([k for _, k in ages])
    for name, values in (
        ("pool age at opening, fresh pools: min / median / p90 / max (PPO steps)", fresh),
        ("the kept policy's share of them (`run.kept_policy`), the same", kept),
        (f"the same, a pool staged {args.stage_after:g} s into the round before", before),
    ):
        if len(values):
            q = np.percentile(values, [0, 50, 90, 100])
            print(f"| {name} | {' / '.join(f'{v:,.0f}' for v in q)} |")
    print(
        f"\n{len(samples)} mid-round checkpoints read; "
        f"{statistics.mean(latencies) * 1000:.0f} ms mean"
    )
    for r, (own, kept_ages) in enumerate(ages, start=1):
        if len(own):
            print(
                f"round {r}: {len(own)} behaviours, ages {min(own):,}–{max(own):,} "
                f"(median {int(np.median(own)):,}); {len(kept_ages)} of the kept policy's"
                + (f", {kept_ages[0]:,} steps old" if len(kept_ages) else "")
            )


def _print_waits(waits: list[float], openings: list[dict | None]) -> None:
    """The End-round wait table: the person's wait (median, p95, max) and its parts, from
    each round's ``opening.json`` (wall seconds; the job's CPU seconds in this process)."""
    print("| End round → next round open (s) | median | p95 | max |")
    print("|---|---:|---:|---:|")
    rows: list[tuple[str, list[float]]] = [("the person's wait (HTTP, polled every 50 ms)", waits)]
    found = [o for o in openings if o is not None]
    if found:
        rows.append(("the worker's: round closed → round opened", [o["waited_s"] for o in found]))
        for part, meaning in PARTS.items():
            values = [o["parts_s"].get(part, 0.0) for o in found]
            rows.append((f"· {part}: {meaning}", values))
        for part in ("sample", "cut", "publish"):  # a pool cut before the round's end
            staged = [o["staged_s"][part] for o in found if "staged_s" in o]
            if staged:
                rows.append((f"cut before the round's end, not waited for: {part}", staged))
        rows.append(("the job's CPU time (worker process)", [o["job_cpu_s"] for o in found]))
    for name, values in rows:
        p50, p95 = np.percentile(values, [50, 95])
        print(f"| {name} | {p50:.2f} | {p95:.2f} | {max(values):.2f} |")
    print()


def _opening(data: Path, session: str, round_index: int) -> dict | None:
    """Where the wait for round `round_index` went (its ``opening.json``; None without)."""
    path = data / round_directory(session, round_index) / OPENING_FILE
    try:
        return dict(json.loads(path.read_text()))
    except (OSError, ValueError):
        return None


def _pool_ages(data: Path, session: str, round_index: int) -> tuple[np.ndarray, np.ndarray]:
    """The ages (PPO steps) of round `round_index`'s behaviours when it opened, from its
    ``pool.json`` (empty when it does not say): those from PPO's latest rollouts or sampled
    from its policy, and those of the kept policy's share (`run.kept_policy`)."""
    directory = data / round_directory(session, round_index)
    try:
        ages = np.asarray(json.loads((directory / "pool.json").read_text())["metadata"]["ages"])
    except (OSError, ValueError, KeyError):
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    sources = load_sources(directory)  # not the whole pool: its behaviours' steps too
    cfg = RunConfig.load(data / "sessions" / session / CONFIG_FILE)
    kept = np.zeros(len(ages), bool) if sources is None else sources == kept_tag(cfg.loop)
    return ages[~kept].astype(np.int64), ages[kept].astype(np.int64)


def _steps_at(points: list[dict], when: float) -> float:
    """PPO steps as of wall-clock `when`, from the learning-curve points (the last before)."""
    steps = [p["ppo_steps"] for p in points if _seconds(p["at"]) <= when]
    return float(max(steps)) if steps else float("nan")


def _seconds(at: str) -> float:
    from datetime import datetime

    return datetime.fromisoformat(at.replace("Z", "+00:00")).timestamp()


def _stage_ahead_ages(
    points: list[dict], opened: list[float], ended: list[float], stage_after: float
) -> np.ndarray:
    """The age each opened round's pool would have had in the earlier design: PPO steps from
    a snapshot `stage_after` s into the round before to that round's end (a round shorter
    than that had its pool sampled at its end: age 0)."""
    ages = []
    for start, end in zip(opened, ended, strict=False):
        staged = start + stage_after
        ages.append(0.0 if staged >= end else _steps_at(points, end) - _steps_at(points, staged))
    return np.asarray(ages)


if __name__ == "__main__":
    main(sys.argv[1:])
