"""How often the walker's preference data showed a split held, round by round.

    python research/pool_splits.py RUN ...            # per round
    python research/pool_splits.py --summary RUN ...  # per run

For each walker-splits case-study run (`docs/results/case-studies/walker/run.sh` makes them),
every step of the fragments in each round's preference dataset
(`checkpoints/round-*/dataset.npz`) is put back into MuJoCo (the observation holds qpos
without x, so the pose is exact) and judged by the splits' rule (`split_posture`): the share
of steps with the thighs >= 90° apart, the share with both feet down, and the share with all
three conditions (a held split's step). A reward model can only learn what its fragments
show; a row of zeros in the last column means the teacher never saw a split to prefer.
Measured with it: docs/results/case-studies/walker/README.md ("What the preference data held").
"""

import argparse
import json
import math
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from groupwise.envs import make_env
from groupwise.envs.body_state import StateReader
from groupwise.envs.scorers import SPLIT_ANGLE, UPRIGHT, WALKER_FEET, split_posture


def shares(base: Any, obs: np.ndarray) -> tuple[float, float, float]:
    """Of the steps in `obs` (..., obs_dim), the shares split >= 90°, with both feet down, and
    held (all three conditions); NaN for no step. `base` is the unwrapped MuJoCo env, whose
    pose is overwritten."""
    read = StateReader(base)
    nq = base.model.nq
    steps = obs.reshape(-1, obs.shape[-1])
    if len(steps) == 0:  # a round that added no fragment
        return math.nan, math.nan, math.nan
    split = down = held = 0
    for o in steps:
        base.data.qpos[1:] = o[: nq - 1]
        mujoco.mj_kinematics(base.model, base.data)
        separation, tilt, feet = split_posture(read())
        split += separation >= SPLIT_ANGLE
        down += feet == len(WALKER_FEET)
        held += separation >= SPLIT_ANGLE and tilt <= UPRIGHT and feet == len(WALKER_FEET)
    return split / len(steps), down / len(steps), held / len(steps)


def _rounds(run: Path) -> list[tuple[int, np.ndarray]]:
    """Per round the observations of the fragments it added to the run's dataset."""
    seen, added = 0, []
    for checkpoint in sorted((run / "checkpoints").glob("round-*")):
        obs = np.load(checkpoint / "dataset.npz")["obs"]
        added.append((int(checkpoint.name.split("-")[1]), obs[seen:]))
        seen = len(obs)
    return added


def summary_table(base: Any, runs: list[Path]) -> list[str]:
    """Per run: the held-split share of each round's new fragments, and the share of the
    final greedy episodes that succeeded."""
    lines = [
        "| run | held-split share of each round's new fragments | final success |",
        "|---|---|---:|",
    ]
    for run in runs:
        held = [shares(base, obs)[2] for _, obs in _rounds(run)]
        final = json.loads((run / "summary.json").read_text())["final"]["success_rate"]
        per_round = " / ".join(f"{h:.3f}" for h in held)
        lines.append(f"| {run.parent.name}/{run.name} | {per_round} | {final:.1f} |")
    return lines


def round_table(base: Any, runs: list[Path]) -> list[str]:
    """Per run and round: fragments added, and their split, feet-down and held shares."""
    lines = [
        "| run | round | fragments | split ≥ 90° | both feet down | all three |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    for run in runs:
        for r, obs in _rounds(run):
            split, down, held = shares(base, obs)
            lines.append(
                f"| {run.name} | {r} | {len(obs)} | {split:.3f} | {down:.3f} | {held:.4f} |"
            )
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", nargs="+", type=Path, help="walker-splits case-study folders")
    parser.add_argument("--summary", action="store_true", help="one row per run")
    args = parser.parse_args(argv)
    missing = [run for run in args.runs if not (run / "checkpoints").is_dir()]
    if missing:
        parser.error(f"{missing[0]}: no checkpoints/ (a `groupwise case-study` output folder?)")
    env = make_env("Walker2d-splits")
    env.reset(seed=0)
    table = summary_table if args.summary else round_table
    print("\n".join(table(env.unwrapped, args.runs)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
