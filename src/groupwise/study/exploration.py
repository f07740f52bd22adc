"""Does exploration put the behaviour in the pool? (issue 20, docs/case-studies.md).

Runs a case-study target's first rounds as `groupwise case-study` does (`run_rounds` over a
`Run`, so pre-training happens where it happens in every run) and measures each round's
pool by its behaviours' target scores: a behaviour's score is its mean per-step target score
(its true return / L, in the target's unit per step: rad for the cheetah's raised front,
rad of separation for the splits, rad/s of backward rotation for the backflip). What the
teacher can tell apart, and what the reward model can learn, is bounded by the pool's
spread (sd) and its best behaviour (max); after each round the greedy policy is scored on
the target (`evaluate_target`) as well.

    python -m groupwise.study.exploration --target halfcheetah-standup --pretrain-steps 100000 \\
        --seed 0 --out runs/explore/cheetah-pre-0
    python -m groupwise.study.exploration --table runs/explore/*     # the markdown table
"""

import argparse
import csv
import dataclasses
import json
import logging
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from groupwise.clips.timing import clip_timing, default_clip_seconds, env_step_seconds
from groupwise.config import LoopConfig, RunConfig
from groupwise.envs import TARGETS, Target
from groupwise.oracles import Feedback
from groupwise.run.headless import feedback_of, run_rounds
from groupwise.run.pretrain import pretrain
from groupwise.run.progress import OnRoundEnd
from groupwise.run.records import RoundRecord
from groupwise.run.run import Run
from groupwise.run.streams import eval_rng
from groupwise.study.case_study import PoolRecorder, evaluate_target

POOLS_FILE = "pools.csv"
SETUP_FILE = "exploration.json"
START_FILE = "before-round-0.json"
"""The greedy policy's target score before round 0 (after pre-training, if any)."""


@dataclass(frozen=True)
class PoolSpread:
    """One round's pool and the policy after the round."""

    round: int
    behaviours: int
    score_mean: float
    """Mean over the pool's behaviours of their mean per-step target score."""
    score_sd: float
    """Their standard deviation: how much there is to tell apart."""
    score_max: float
    """The best behaviour's: whether the pool holds the behaviour at all."""
    eval_score_mean: float
    """The greedy policy's episode target score after the round (mean over the episodes)."""
    success_rate: float
    """Share of those episodes at or above the target's threshold."""
    env_steps: int
    """PPO steps so far, pre-training included."""


def measure(cfg: RunConfig, target: Target, out: Path, eval_episodes: int = 5) -> list[PoolSpread]:
    """Run `cfg`'s rounds (pre-training first when it asks) into `out` and measure every
    round's pool and policy (module docstring); writes ``pools.csv`` and the greedy policy's
    target score before round 0 (``before-round-0.json``).

    Raises:
        ValueError: the config's env is not the target's.
    """
    if cfg.loop.env != target.env:
        raise ValueError(f"the config's env {cfg.loop.env!r} is not {target.name}'s {target.env}")
    own = feedback_of(cfg)
    recorder = PoolRecorder(own.queries)
    feedback = Feedback(recorder, own.teacher)
    rows: list[PoolSpread] = []
    with Run.create(cfg, out) as run:
        pretrain(run)
        before = evaluate_target(
            run.make_env,
            run.agent.policy(deterministic=True),
            eval_episodes,
            eval_rng(cfg.loop.seed),
        )
        start = {
            "eval_score_mean": float(before.scores.mean()),
            "success_rate": before.success_rate(target),
            "env_steps": run.agent.num_timesteps,
        }
        (out / START_FILE).write_text(json.dumps(start) + "\n")

        def scored(record: RoundRecord) -> None:
            scores = recorder.scores[record.round]
            evaluation = evaluate_target(
                run.make_env,
                run.agent.policy(deterministic=True),
                eval_episodes,
                eval_rng(cfg.loop.seed),
            )
            rows.append(
                PoolSpread(
                    round=record.round,
                    behaviours=len(scores),
                    score_mean=float(scores.mean()),
                    score_sd=float(scores.std()),
                    score_max=float(scores.max()),
                    eval_score_mean=float(evaluation.scores.mean()),
                    success_rate=evaluation.success_rate(target),
                    env_steps=record.env_steps,
                )
            )
            _write(out / POOLS_FILE, rows)

        run_rounds(run, feedback, OnRoundEnd(scored))
    return rows


def _write(path: Path, rows: Sequence[PoolSpread]) -> None:
    with path.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=[f.name for f in dataclasses.fields(PoolSpread)])
        writer.writeheader()
        writer.writerows(dataclasses.asdict(r) for r in rows)


def config_for(
    target: Target,
    *,
    pretrain_steps: int,
    seed: int,
    rounds: int = 3,
    comparisons: int = 30,
    steps_per_round: int = 20_480,
    pool_size: int = 100,
    dm: str = "groupwise",
    label_error: float | None = 0.12,
    exploration_fraction: float | None = None,
) -> RunConfig:
    """The case study's config (`groupwise case-study`'s defaults: 1.5 s behaviours, the
    reward members on observations alone) with a fixed pool size, a short run and, by
    default, the teacher calibrated to people (`TeacherConfig.label_error`); the pools'
    share of random actions is `exploration_fraction` (None: the study's 0.05)."""
    base = RunConfig()
    length = clip_timing(env_step_seconds(target.env), default_clip_seconds(target.base)).steps
    loop = dataclasses.replace(
        base.loop,
        env=target.env,
        oracle=dm,
        comparisons=comparisons,
        rounds=rounds,
        steps=steps_per_round * rounds,
        fragment_length=length,
        pool_size=pool_size,
        exploration_fraction=(
            base.loop.exploration_fraction if exploration_fraction is None else exploration_fraction
        ),
        eval_episodes=0,
        seed=seed,
    )
    return dataclasses.replace(
        base,
        loop=LoopConfig(**dataclasses.asdict(loop)),
        reward=dataclasses.replace(base.reward, use_actions=False),
        teacher=dataclasses.replace(base.teacher, label_error=label_error),
        training=dataclasses.replace(base.training, pretrain_steps=pretrain_steps),
        ppo=dataclasses.replace(base.ppo, tensorboard=False),
    )


def table(directories: Sequence[Path]) -> str:
    """The markdown table of measured runs: one line per run and round."""
    lines = [
        "| target | exploration | seed | round | pool sd | pool max | eval score | success |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for directory in directories:
        setup = json.loads((directory / SETUP_FILE).read_text())
        with (directory / POOLS_FILE).open() as handle:
            for row in csv.DictReader(handle):
                lines.append(
                    f"| {setup['target']} | {_variant(setup)} | {setup['seed']} "
                    f"| {row['round']} | {float(row['score_sd']):.3f} "
                    f"| {float(row['score_max']):.3f} | {float(row['eval_score_mean']):.3f} "
                    f"| {float(row['success_rate']):.0%} |"
                )
    return "\n".join(lines)


def _variant(setup: dict[str, Any]) -> str:
    parts = []
    if setup["pretrain_steps"]:
        parts.append(f"pre-training {setup['pretrain_steps'] // 1000}k")
    fraction = setup.get("exploration_fraction")
    if fraction is not None:
        parts.append(f"{fraction:.0%} random actions")
    return ", ".join(parts) or "none"


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m groupwise.study.exploration")
    parser.add_argument("--target", choices=sorted(TARGETS))
    parser.add_argument("--pretrain-steps", type=int, default=0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--comparisons", type=int, default=30)
    parser.add_argument("--steps-per-round", type=int, default=20_480)
    parser.add_argument("--pool", type=int, default=100)
    parser.add_argument("--exploration-fraction", type=float)
    parser.add_argument("--out", type=Path)
    parser.add_argument("--table", type=Path, nargs="+", help="print the table of these runs")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(name)s: %(message)s")
    if args.table:
        print(table(args.table))
        return 0
    if args.target is None or args.out is None:
        parser.error("--target and --out are needed (or --table DIR ...)")
    target = TARGETS[args.target]
    cfg = config_for(
        target,
        pretrain_steps=args.pretrain_steps,
        seed=args.seed,
        rounds=args.rounds,
        comparisons=args.comparisons,
        steps_per_round=args.steps_per_round,
        pool_size=args.pool,
        exploration_fraction=args.exploration_fraction,
    )
    args.out.mkdir(parents=True, exist_ok=True)
    setup = {
        "target": target.name,
        "pretrain_steps": args.pretrain_steps,
        "seed": args.seed,
        "exploration_fraction": args.exploration_fraction,
    }
    (args.out / SETUP_FILE).write_text(json.dumps(setup) + "\n")
    tick = time.perf_counter()
    measure(cfg, target, args.out)
    print(table([args.out]))
    print(f"{time.perf_counter() - tick:.0f} s", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
