"""Benchmark: how much a Sakoe–Chiba band or a coarser time step changes the behaviour tree,
and how much time it saves (issue 22, deliverable 4).

Pools of Hopper behaviours of the env's default 1.5 s (188 steps; random policy with the
app's 0.25 exploration, or `--policy` checkpoints), z-scored features as a round uses them.
Per option of `dtw_matrix` (`window` in steps, `stride` in steps per coarse step) against
exact full-resolution DTW: the cophenetic correlation of the two complete-linkage
dendrograms (Pearson's r of their cophenetic distances), the adjusted Rand index of the
default tree's level-1 and level-2 clusters (each leaf labelled by its ancestor at that
level), and the median seconds of the distance matrix. Mean over pools.

    python -m benchmarks dtw_options
    python benchmarks/dtw_options.py [--n 200] [--pools 3] [--policy random ...] [--repeats 1]
"""

import argparse
import os
import statistics
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.cluster.hierarchy import cophenet
from sklearn.metrics import adjusted_rand_score

from groupwise.behaviour import TreeConfig, build_tree, dtw_matrix, linkage_matrix, pool_features
from groupwise.behaviour.dtw import warm_up
from groupwise.behaviour.tree import BehaviourTree
from groupwise.clips.timing import env_clip_timing
from groupwise.envs import make_env
from groupwise.pool.sampling import sample_pool
from groupwise.rl.policy_files import load_policy
from groupwise.types import FloatArray


@dataclass(frozen=True)
class Option:
    name: str
    window: int | None
    stride: int


def options(length: int) -> list[Option]:
    """Exact DTW, bands of 20 % and 10 % of L, strides 2, 3 and 4, and stride 2 in a 20 %
    band (20 % of L: `TreeConfig.dtw_band`'s default)."""
    w20, w10 = round(0.2 * length), round(0.1 * length)
    return [
        Option("exact", None, 1),
        Option(f"band {w20} (20 %)", w20, 1),
        Option(f"band {w10} (10 %)", w10, 1),
        Option("stride 2", None, 2),
        Option("stride 3", None, 3),
        Option("stride 4", None, 4),
        Option(f"stride 2, band {w20}", w20, 2),
    ]


CLOSE = {"cophenetic r": 0.95, "ARI level 1": 0.7, "ARI level 2": 0.7}
"""What "the tree stays close" means: every measure at least this (mean over pools): the
cophenetic distances nearly proportional, and the level-1 and level-2 groups a person sees
mostly the same."""


def level_labels(tree: BehaviourTree, level: int) -> np.ndarray:
    """(N,) each behaviour's ancestor at `level`, as an index into `tree.at_level(level)`."""
    labels = np.zeros(tree.root.size, dtype=np.int64)
    for k, node in enumerate(tree.at_level(level)):
        labels[list(node.leaves)] = k
    return labels


def compare(exact: FloatArray, other: FloatArray) -> dict[str, float]:
    """Cophenetic r and the level-1 / level-2 ARIs of the trees of two distance vectors."""
    r = float(np.corrcoef(cophenet(linkage_matrix(exact)), cophenet(linkage_matrix(other)))[0, 1])
    a, b = build_tree(exact, TreeConfig()), build_tree(other, TreeConfig())
    return {
        "cophenetic r": r,
        "ARI level 1": float(adjusted_rand_score(level_labels(a, 1), level_labels(b, 1))),
        "ARI level 2": float(adjusted_rand_score(level_labels(a, 2), level_labels(b, 2))),
    }


def sample_features(
    policy_spec: str, n: int, length: int, seed: int, env: str = "Hopper"
) -> list[FloatArray]:
    pool = sample_pool(
        lambda: make_env(env),
        load_policy(policy_spec, env),
        n,
        length,
        np.random.default_rng(seed),
        exploration_fraction=0.25,
    )
    return pool_features(pool.fragments)


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--n", type=int, default=200, help="behaviours per pool")
    parser.add_argument("--pools", type=int, default=2, help="pools per policy")
    parser.add_argument("--policy", nargs="+", default=["random"], help="random or checkpoints")
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--seed", type=int, default=0)
    # argv None (as `python -m benchmarks` calls it) means the defaults, not sys.argv
    args = parser.parse_args([] if argv is None else list(argv))

    length = env_clip_timing("Hopper").steps
    opts = options(length)
    warm_up()
    measures: dict[str, list[dict[str, float]]] = {o.name: [] for o in opts}
    for p, spec in enumerate(args.policy):
        for k in range(args.pools):
            feats = sample_features(spec, args.n, length, args.seed + 1000 * p + k)
            exact = dtw_matrix(feats)
            for o in opts:
                runs = []
                for _ in range(args.repeats):
                    start = time.perf_counter()
                    d = dtw_matrix(feats, window=o.window, stride=o.stride)
                    runs.append(time.perf_counter() - start)
                row = compare(exact, d)
                row["seconds"] = statistics.median(runs)
                measures[o.name].append(row)

    base = statistics.mean(m["seconds"] for m in measures["exact"])
    head = ["option", *CLOSE, "seconds", "time saved", "close"]
    print(
        f"DTW options on Hopper, L = {length} (1.5 s), N = {args.n}, "
        f"{len(args.policy) * args.pools} pools ({', '.join(args.policy)}), "
        f"{os.cpu_count()} CPUs; mean over pools; close: "
        + ", ".join(f"{k} >= {v}" for k, v in CLOSE.items())
        + "\n"
    )
    print("| " + " | ".join(head) + " |")
    print("|---|" + "---:|" * (len(head) - 1))
    for o in opts:
        mean = {k: statistics.mean(m[k] for m in measures[o.name]) for k in measures[o.name][0]}
        close = all(mean[k] >= v for k, v in CLOSE.items())
        cells = [f"{mean[k]:.3f}" for k in CLOSE]
        saved = 1.0 - mean["seconds"] / base
        print(
            f"| {o.name} | "
            + " | ".join(cells)
            + f" | {mean['seconds']:.2f} | {saved:.0%} | {'yes' if close else 'no'} |"
        )


if __name__ == "__main__":
    main(sys.argv[1:])
