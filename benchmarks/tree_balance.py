"""Benchmark: how balanced the behaviour tree is on pools of random and trained policies
(issues 22 and 40).

Two presets. "quick" (default, ~5 min on 2 cores): one seeded headless Hopper run
(`groupwise train --env Hopper --rounds 2 --comparisons 30 --steps 40000 --dm groupwise
--seed 0`, 20,000 PPO steps a round); "full" (~30 min): the four envs of issue 22 (`--rounds
3 --comparisons 60 --steps 90000`). Runs are written to `--runs` and reused when there. From
the random policy (round 0) and each round's checkpoint (rounds >= 1) a pool is sampled as
the app samples one (the env's default clip duration, 0.25 exploration, the run's
oversampling by ensemble uncertainty), of each `--n` size, and its DTW distances measured
as the app measures them (`TreeConfig.dtw_band`; cached in `--runs`/pools/ENV-rR-nN.npz).

Per pool and tree config:
- top: the number of top-level clusters (the root's children) and the largest one's share
  of the leaves (L3 = top, then levels 2 and 1);
- 2 clicks: the share of top-level clusters offering a group candidate (2-8 behaviours)
  within two clicks: the cluster itself holds at most 8, or, focused (one click), one of
  the rings it then fills has a node of 2-8 (the second click picks it);
- 1 ring: the same without focus: the cluster or one of its children;
- groups: the selectable groups of `group_candidates` (level 1-2 nodes of 2-8 leaves).

    python -m benchmarks tree_balance                        # quick: Hopper, N 100 and 1,000
    python benchmarks/tree_balance.py --preset full --n 100  # issue 22's four envs
"""

import argparse
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from groupwise.behaviour import (
    TreeConfig,
    band_window,
    build_tree,
    dtw_matrix,
    group_candidates,
    pool_features,
)
from groupwise.behaviour.tree import BehaviourTree, TreeNode
from groupwise.clips.timing import env_clip_timing
from groupwise.config import RunConfig
from groupwise.pool.sampling import sample_pool
from groupwise.preferences.judgement import MAX_GROUP
from groupwise.run.run import Run

PRESETS = {
    "quick": (("Hopper",), ["--rounds", "2", "--comparisons", "30", "--steps", "40000"]),
    "full": (
        ("Hopper", "HalfCheetah", "Walker2d", "GridWorld"),
        ["--rounds", "3", "--comparisons", "60", "--steps", "90000"],
    ),
}
"""Preset -> (envs, `groupwise train` arguments of each env's run)."""
CONFIGS = {
    "no caps": TreeConfig(balance=None),
    "caps (issue 22)": TreeConfig(top_balance=None),
    "+ top cap (now)": TreeConfig(),
}


def train(env: str, out: Path, seed: int, flags: Sequence[str]) -> None:
    """A short headless run of `env` into `out`, unless one is there."""
    if (out / "checkpoints").is_dir():
        return
    cmd = [sys.executable, "-m", "groupwise.cli", "train", "--env", env, *flags]
    subprocess.run([*cmd, "--dm", "groupwise", "--seed", str(seed), "--out", str(out), "-q"],
                   check=True)  # fmt: skip


def pools(run_dir: Path, cache: Path, size: int, seed: int) -> list[tuple[int, Path]]:
    """(round, file) of the pool sampled before each round: from the random policy (round
    0), then from each checkpoint; sampled once, then read from `cache`."""
    cfg = RunConfig.load(run_dir / "config.json")
    length = env_clip_timing(cfg.loop.env).steps
    rounds = sorted(int(p.name.split("-")[1]) for p in (run_dir / "checkpoints").glob("round-*"))
    out = []
    for after in [-1, *rounds]:
        path = cache / f"{run_dir.name}-r{after + 1}-n{size}.npz"
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
            features = pool_features(pool.fragments)
            tree = TreeConfig()  # the app's DTW band and time step
            window = band_window(tree.dtw_band, max(len(f) for f in features))
            distances = dtw_matrix(features, window=window, stride=tree.dtw_stride)
            cache.mkdir(parents=True, exist_ok=True)
            np.savez(path, distances=distances, true=pool.true_returns, length=length)
        out.append((after + 1, path))
    return out


def shares(tree: BehaviourTree) -> list[float]:
    """The largest node's share of the leaves at levels top - 1, ..., 1."""
    n = tree.root.size
    return [max(x.size for x in tree.at_level(lv)) / n for lv in range(tree.levels - 1, 0, -1)]


def offers_group(node: TreeNode, depth: int) -> bool:
    """Whether `node` holds at most MAX_GROUP behaviours, or a node 1..depth levels below it
    holds 2..MAX_GROUP (a group to pick)."""
    if node.size <= MAX_GROUP:
        return True
    rings, below = [node], []
    for _ in range(depth):
        rings = [c for x in rings for c in x.children]
        below.extend(rings)
    return any(2 <= x.size <= MAX_GROUP for x in below)


def within_reach(tree: BehaviourTree, depth: int) -> float:
    """The share of top-level clusters that offer a group within `depth` rings of them."""
    top = tree.root.children
    return sum(offers_group(t, depth) for t in top) / len(top)


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--preset", choices=list(PRESETS), default="quick")
    parser.add_argument("--envs", nargs="+", help="only these of the preset's envs")
    parser.add_argument("--runs", type=Path, default=Path("runs/tree-balance"))
    parser.add_argument("--n", type=int, nargs="+", default=[100, 1000], help="pool sizes")
    parser.add_argument("--seed", type=int, default=0, help="the training runs' seed")
    parser.add_argument("--pool-seed", type=int, default=7, help="the pools' sampling seed")
    # argv None (as `python -m benchmarks` calls it) means the defaults, not sys.argv
    args = parser.parse_args([] if argv is None else list(argv))
    envs, flags = PRESETS[args.preset]

    print(
        "Per pool: top-level clusters (count, largest share), the largest cluster's share of "
        "the leaves at levels 3 (top), 2 and 1, the share of top-level clusters offering a "
        "group of 2-8 within two clicks (focus, pick) and within one ring (no focus), and the "
        "selectable groups. Round r's pool comes from the policy after r rounds (0: random); "
        "4 levels.\n"
    )
    head = ["env", "N", "round", "config", "top", "L3", "L2", "L1", "2 clicks", "1 ring", "groups"]
    print("| " + " | ".join(head) + " |")
    print("|---|---:|---:|---|" + "---:|" * (len(head) - 4))
    for env in args.envs or envs:
        run_dir = args.runs / env
        train(env, run_dir, args.seed, flags)
        for n in args.n:
            for r, path in pools(run_dir, args.runs / "pools", n, args.pool_seed):
                distances = np.load(path)["distances"]
                for name, cfg in CONFIGS.items():
                    tree = build_tree(distances, cfg)
                    cells = [
                        str(len(tree.root.children)),
                        *(f"{s:.2f}" for s in shares(tree)),
                        f"{within_reach(tree, 2):.2f}",
                        f"{within_reach(tree, 1):.2f}",
                        str(len(group_candidates(tree))),
                    ]
                    print(f"| {env} | {n} | {r} | {name} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main(sys.argv[1:])
