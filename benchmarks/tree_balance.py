"""Benchmark: how balanced the behaviour tree is on pools of trained policies (issue 22).

For each env, a short headless run (`groupwise train --rounds 3 --comparisons 60 --steps
90000 --dm groupwise --seed 0`, written to `--runs`, reused when there) gives the policy
and reward model after each round; from each checkpoint (and the random policy: round 0)
a pool is sampled as the app samples one (100 behaviours of the env's default clip
duration, 0.25 exploration, the run's oversampling by ensemble uncertainty) and its exact
DTW distances are kept (`--runs`/pools/ENV-rR.npz). Per pool and tree config: the
largest node's share of the leaves at each level (top level = the root's children) and
the selectable groups (level 1-2 nodes of 2-8 leaves, `group_candidates`).

    python -m benchmarks tree_balance                    # on demand: trains first (~30 min)
    python benchmarks/tree_balance.py [--envs Hopper ...] [--runs runs/tree-balance]
"""

import argparse
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from groupwise.behaviour import TreeConfig, build_tree, dtw_matrix, group_candidates, pool_features
from groupwise.behaviour.tree import BehaviourTree
from groupwise.clips.timing import env_clip_timing
from groupwise.config import RunConfig
from groupwise.pool.sampling import sample_pool
from groupwise.run.run import Run

ENVS = ("Hopper", "HalfCheetah", "Walker2d", "GridWorld")
TRAIN = ["--rounds", "3", "--comparisons", "60", "--steps", "90000", "--dm", "groupwise"]
CONFIGS = {
    "counts (before)": TreeConfig(balance=None),
    "counts + caps (now)": TreeConfig(),
    "ward, no caps": TreeConfig(method="ward", balance=None),
    "ward + caps": TreeConfig(method="ward"),
}


def train(env: str, out: Path, seed: int) -> None:
    """A short headless run of `env` into `out`, unless one is there."""
    if (out / "checkpoints").is_dir():
        return
    cmd = [sys.executable, "-m", "groupwise.cli", "train", "--env", env, *TRAIN]
    subprocess.run([*cmd, "--seed", str(seed), "--out", str(out), "-q"], check=True)


def pools(run_dir: Path, cache: Path, size: int, seed: int) -> list[tuple[int, Path]]:
    """(round, file) of the pool sampled before each round: from the random policy (round
    0), then from each checkpoint; sampled once, then read from `cache`."""
    cfg = RunConfig.load(run_dir / "config.json")
    length = env_clip_timing(cfg.loop.env).steps
    rounds = sorted(int(p.name.split("-")[1]) for p in (run_dir / "checkpoints").glob("round-*"))
    out = []
    for after in [-1, *rounds]:
        path = cache / f"{run_dir.name}-r{after + 1}.npz"
        if not path.exists():
            run = Run.create(cfg)
            run.out = run_dir
            run.restore(after=after)
            pool = sample_pool(
                run.make_env,
                run.agent.policy(),
                size,
                length,
                np.random.default_rng([seed, after + 1]),
                round_index=after + 1,
                exploration_fraction=0.25,
                oversample=cfg.loop.pool_oversample,
                max_windows=cfg.loop.pool_windows_max,
                ensemble=run.ensemble,
            )
            distances = dtw_matrix(pool_features(pool.fragments))
            cache.mkdir(parents=True, exist_ok=True)
            np.savez(path, distances=distances, true=pool.true_returns, length=length)
        out.append((after + 1, path))
    return out


def shares(tree: BehaviourTree) -> list[float]:
    """The largest node's share of the leaves at levels top - 1, ..., 1."""
    n = tree.root.size
    return [max(x.size for x in tree.at_level(lv)) / n for lv in range(tree.levels - 1, 0, -1)]


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--envs", nargs="+", default=list(ENVS))
    parser.add_argument("--runs", type=Path, default=Path("runs/tree-balance"))
    parser.add_argument("--n", type=int, default=100, help="behaviours per pool (the app's)")
    parser.add_argument("--seed", type=int, default=0, help="the training runs' seed")
    parser.add_argument("--pool-seed", type=int, default=7, help="the pools' sampling seed")
    # argv None (as `python -m benchmarks` calls it) means the defaults, not sys.argv
    args = parser.parse_args([] if argv is None else list(argv))

    print(
        f"Largest cluster's share of the leaves per level (L3 = top level) and selectable "
        f"2-8-leaf groups at levels 1-2; N = {args.n}, 4 levels; pools of round r come from "
        f"the policy after r rounds of a short run (round 0: random).\n"
    )
    head = ["env", "round", "config", "L3", "L2", "L1", "groups"]
    print("| " + " | ".join(head) + " |")
    print("|---|---:|---|" + "---:|" * (len(head) - 3))
    for env in args.envs:
        run_dir = args.runs / env
        train(env, run_dir, args.seed)
        for r, path in pools(run_dir, args.runs / "pools", args.n, args.pool_seed):
            distances = np.load(path)["distances"]
            for name, cfg in CONFIGS.items():
                tree = build_tree(distances, cfg)
                cells = [f"{s:.2f}" for s in shares(tree)]
                groups = len(group_candidates(tree))
                print(f"| {env} | {r} | {name} | " + " | ".join(cells) + f" | {groups} |")


if __name__ == "__main__":
    main(sys.argv[1:])
