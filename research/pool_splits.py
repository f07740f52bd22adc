"""How often the walker's preference data showed a split held, round by round.

    python docs/results/case-studies/walker/pool_splits.py RUN ...            # per round
    python docs/results/case-studies/walker/pool_splits.py --summary RUN ...  # per run

For each walker-splits case-study run, every step of the fragments in each round's
preference dataset (`checkpoints/round-*/dataset.npz`) is put back into MuJoCo (the
observation holds qpos without x, so the pose is exact) and judged by the splits' rule
(`split_posture`): the share of steps with the thighs >= 90° apart, the share with both
feet down, and the share with all three conditions (a held split's step). A reward model
can only learn what its fragments show; a row of zeros in the last column means the
teacher never saw a split to prefer.
"""

import json
import math
import sys
from pathlib import Path

import mujoco
import numpy as np

from groupwise.envs import make_env
from groupwise.envs.body_state import StateReader
from groupwise.envs.scorers import SPLIT_ANGLE, UPRIGHT, WALKER_FEET, split_posture


def shares(env, obs: np.ndarray) -> tuple[float, float, float]:
    base = env.unwrapped
    read = StateReader(base)
    nq = base.model.nq
    split = down = held = 0
    for o in obs.reshape(-1, obs.shape[-1]):
        base.data.qpos[1:] = o[: nq - 1]
        mujoco.mj_kinematics(base.model, base.data)
        separation, tilt, feet = split_posture(read())
        split += separation >= SPLIT_ANGLE
        down += feet == len(WALKER_FEET)
        held += separation >= SPLIT_ANGLE and tilt <= UPRIGHT and feet == len(WALKER_FEET)
    n = len(obs.reshape(-1, obs.shape[-1]))
    if n == 0:  # a round that added no fragment
        return math.nan, math.nan, math.nan
    return split / n, down / n, held / n


def summary(env, runs: list[Path]) -> None:
    """Per run: the held-split share of each round's new fragments, and whether the run's
    final greedy policy succeeded (3 of 5 episodes)."""
    print("| run | held-split share of each round's new fragments | final success |")
    print("|---|---|---:|")
    for run in runs:
        seen, held = 0, []
        for checkpoint in sorted((run / "checkpoints").glob("round-*")):
            obs = np.load(checkpoint / "dataset.npz")["obs"]
            held.append(shares(env, obs[seen:])[2])
            seen = len(obs)
        final = json.loads((run / "summary.json").read_text())["final"]["success_rate"]
        print(f"| {run.parent.name}/{run.name} | {' / '.join(f'{h:.3f}' for h in held)} "
              f"| {final:.1f} |", flush=True)


def main() -> None:
    env = make_env("Walker2d-splits")
    env.reset(seed=0)
    if sys.argv[1] == "--summary":
        summary(env, [Path(run) for run in sys.argv[2:]])
        return
    print("| run | round | fragments | split ≥ 90° | both feet down | all three |")
    print("|---|---:|---:|---:|---:|---:|")
    for run in map(Path, sys.argv[1:]):
        seen = 0
        for checkpoint in sorted((run / "checkpoints").glob("round-*")):
            data = np.load(checkpoint / "dataset.npz")
            obs = data["obs"][seen:]  # the fragments this round added
            seen = len(data["obs"])
            split, down, held = shares(env, obs)
            print(f"| {run.name} | {int(checkpoint.name.split('-')[1])} | {len(obs)} "
                  f"| {split:.3f} | {down:.3f} | {held:.4f} |", flush=True)


if __name__ == "__main__":
    main()
