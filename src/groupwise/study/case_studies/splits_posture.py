"""The walker's posture under a case-study run's greedy policy: why a split is not held.

    python -m groupwise.study.case_studies.splits_posture RUN_DIR [RUN_DIR ...] [--round R]

For each ``groupwise case-study --target walker-splits`` run directory: the policy of its
last round (or round R) replays the case study's evaluation episodes (the same reset
seeds, `run.streams.eval_rng`), and a Markdown row gives the share of steps at which each
condition of a held split holds (`envs.scorers.SplitsScorer`): the thighs at least 90°
apart, the torso within 60° of vertical, 0, 1 or 2 feet on the floor, and all three at
once; how often a held split broke (per 1,000 steps, by the condition that failed at the
break); then the median separation and tilt, degrees. A run that never holds a split shows
which condition its policy settled without; one whose split breaks often, which condition
it wobbles about.
"""

import argparse
import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import cast

import numpy as np
from gymnasium.envs.mujoco.mujoco_env import MujocoEnv

from groupwise.envs import TARGETS, make_env
from groupwise.envs.body_state import BodyState
from groupwise.envs.scorers import SPLIT_ANGLE, UPRIGHT, WALKER_FEET, split_posture
from groupwise.rl.policy_files import load_policy
from groupwise.run.checkpoint import checkpoint_dir
from groupwise.run.run import CONFIG_FILE
from groupwise.run.streams import eval_rng
from groupwise.study.case_studies.target_evaluation import evaluate_target
from groupwise.types import FloatArray

HEADER = (
    "| run | round | steps | split ≥ 90° | upright (≤ 60°) | feet down 0 / 1 / 2 | all three "
    "| breaks per 1,000 steps: separation / tilt / feet | median separation | median tilt |\n"
    "|---|---:|---:|---:|---:|---|---:|---|---:|---:|"
)


def posture_shares(
    separation: FloatArray,
    tilt: FloatArray,
    feet: np.ndarray,
    lengths: Sequence[int] | None = None,
) -> dict[str, float]:
    """Shares of steps by each condition of a held split, the breaks of a held split per
    1,000 steps by the condition that failed (a break can fail more than one), and the
    medians (radians), from per-step thigh separation and torso tilt (rad, ≥ 0) and feet on
    the floor (0–2). `lengths`: the episodes' lengths when the steps are several episodes'
    end to end (default: one episode), so that no break is counted where one episode ends
    and the next begins.

    Raises:
        ValueError: no steps, arrays of different lengths, or `lengths` not summing to them.
    """
    if len(separation) == 0 or not len(separation) == len(tilt) == len(feet):
        raise ValueError(f"need equal, non-empty arrays, got {len(separation)}, {len(tilt)}, "
                         f"{len(feet)}")  # fmt: skip
    split, upright = separation >= SPLIT_ANGLE, tilt <= UPRIGHT
    down = feet == len(WALKER_FEET)
    held = split & upright & down
    ended = held[:-1] & ~held[1:]
    starts = np.cumsum(lengths if lengths is not None else [len(held)])
    if starts[-1] != len(held):
        raise ValueError(f"episodes of {starts[-1]} steps in all, for {len(held)} steps")
    ended[starts[:-1] - 1] = False  # an episode's first step follows no step of its own
    broke = np.flatnonzero(ended) + 1  # the steps at which a hold ended
    per_1000 = 1000.0 / len(separation)
    return {
        "steps": float(len(separation)),
        "split": float(split.mean()),
        "upright": float(upright.mean()),
        **{f"feet_{k}": float((feet == k).mean()) for k in range(len(WALKER_FEET) + 1)},
        "all": float(held.mean()),
        "breaks_split": float((~split[broke]).sum() * per_1000),
        "breaks_tilt": float((~upright[broke]).sum() * per_1000),
        "breaks_feet": float((~down[broke]).sum() * per_1000),
        "separation": float(np.median(separation)),
        "tilt": float(np.median(tilt)),
    }


def replay_posture(run: Path, round_index: int | None = None) -> tuple[int, dict[str, float]]:
    """The round replayed (the last by default) and `posture_shares` over its evaluation
    episodes, as the case study evaluated them (module docstring)."""
    config = json.loads((run / CONFIG_FILE).read_text())
    loop = config["loop"]
    target = TARGETS["walker-splits"]
    if loop["env"] != target.env:
        raise ValueError(f"{run} is a run on {loop['env']}, not the walker's splits")
    summary = json.loads((run / "summary.json").read_text())
    episodes = len(summary["final"]["scores"])
    rounds = sorted(int(p.name.split("-")[1]) for p in (run / "checkpoints").glob("round-*"))
    chosen = rounds[-1] if round_index is None else round_index
    policy = load_policy(str(checkpoint_dir(run, chosen)), target.env, deterministic=True)
    factory = lambda: make_env(target.env)  # noqa: E731
    evaluation = evaluate_target(factory, policy, episodes, eval_rng(loop["seed"]))
    steps: list[tuple[float, float, int]] = []
    lengths = [len(actions) for actions in evaluation.actions]
    for seed, actions in zip(evaluation.reset_seeds, evaluation.actions, strict=True):
        env = factory()  # the episode again, its actions replayed, to read every state
        try:
            env.reset(seed=seed)
            for action in actions:
                env.step(action)
                steps.append(split_posture(BodyState.read(cast(MujocoEnv, env.unwrapped))))
        finally:
            env.close()
    separation, tilt, feet = (np.array(column) for column in zip(*steps, strict=True))
    return chosen, posture_shares(separation, tilt, feet, lengths)


def markdown_row(run: Path, chosen: int, shares: dict[str, float]) -> str:
    feet = " / ".join(f"{shares[f'feet_{k}']:.2f}" for k in range(len(WALKER_FEET) + 1))
    breaks = " / ".join(f"{shares[f'breaks_{c}']:.1f}" for c in ("split", "tilt", "feet"))
    return (
        f"| {run.name} | {chosen} | {int(shares['steps'])} | {shares['split']:.2f} "
        f"| {shares['upright']:.2f} | {feet} | **{shares['all']:.2f}** | {breaks} "
        f"| {math.degrees(shares['separation']):.0f}° | {math.degrees(shares['tilt']):.0f}° |"
    )


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", nargs="+", type=Path, help="walker-splits case-study runs")
    parser.add_argument(
        "--round", type=int, help="the round whose policy to replay (default: last)"
    )
    args = parser.parse_args(argv)
    print(HEADER)
    for run in args.runs:
        print(markdown_row(run, *replay_posture(run, args.round)), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
