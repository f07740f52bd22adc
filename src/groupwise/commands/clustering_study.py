"""`groupwise clustering-study`: HC vs PCA vs t-SNE groups of behaviours (SPEC §4)."""

import argparse
import json
from pathlib import Path

from groupwise.commands.arguments import UsageError, non_negative_int, positive_int, writable_dir

REPORT = "clustering.md"
FIGURE = "clustering.png"
DATA = "clustering.json"


def register(subparsers: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    study = subparsers.add_parser(
        "clustering-study",
        help="compare the return-consistency of HC, PCA and t-SNE clusters of behaviours",
    )
    study.add_argument("--env", required=True, help="env with a true reward, e.g. Hopper")
    study.add_argument("--reps", type=positive_int, default=10, help="repetitions")
    study.add_argument("--n", type=positive_int, default=50, help="trajectories per repetition")
    study.add_argument(
        "--windows", type=positive_int, default=1, help="behaviours taken from each trajectory"
    )
    study.add_argument("--length", type=positive_int, default=30, help="steps per behaviour")
    study.add_argument(
        "--clusters", type=positive_int, default=10, help="target clusters for DBSCAN"
    )
    study.add_argument(
        "--policies",
        nargs="*",
        default=[],
        metavar="CHECKPOINT_DIR",
        help="partly trained policies to mix with random ones (default: biased random ones)",
    )
    study.add_argument(
        "--bands",
        choices=["linear", "geometric", "counts"],
        default="linear",
        help="level bands of the HC tree (SPEC §4; the paper's study used linear)",
    )
    study.add_argument(
        "--hc-level",
        type=positive_int,
        default=2,
        help="tree level whose nodes are HC's clusters (1 = the finest groups; default 2)",
    )
    study.add_argument("--seed", type=non_negative_int, default=0, help="random seed")
    study.add_argument("--out", type=Path, required=True, help="output directory")
    study.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    study.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from groupwise.behaviour import TreeConfig
    from groupwise.rl.policy_files import load_policy
    from groupwise.study.clustering.plot import plot_variances
    from groupwise.study.clustering.policy_mix import mixed_policies
    from groupwise.study.clustering.report import markdown_table, to_json
    from groupwise.study.clustering.runner import ClusteringStudyConfig, run_clustering_study

    try:
        cfg = ClusteringStudyConfig(
            env=args.env,
            reps=args.reps,
            trajectories=args.n,
            windows=args.windows,
            length=args.length,
            target_clusters=args.clusters,
            checkpoints=tuple(args.policies),
            tree=TreeConfig(bands=args.bands),
            hc_level=args.hc_level,
        )
        rng = np.random.default_rng(args.seed)
        policies = mixed_policies(
            cfg.env, cfg.checkpoints, cfg.biased_policies, cfg.bias_scale, rng, load_policy
        )
    except (ValueError, OSError) as error:
        raise UsageError(str(error)) from None
    out = writable_dir(args.out)
    try:
        result = run_clustering_study(cfg, policies, rng, show_progress=not args.quiet)
    except ValueError as error:  # e.g. episodes too short for the windows asked for
        raise UsageError(str(error)) from None
    table = markdown_table(result)
    (out / REPORT).write_text(table)
    (out / DATA).write_text(json.dumps({**to_json(result), "seed": args.seed}, indent=1))
    plot_variances(result, out / FIGURE)
    print(f"{table}\nreport: {out / REPORT}\nfigure: {out / FIGURE}")
    return 0
