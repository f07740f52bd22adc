"""`groupwise pool`: prepare a behaviour pool (clips, distances, tree) into a directory."""

import argparse
from pathlib import Path

from groupwise.commands.arguments import UsageError, non_negative_int, positive_int, writable_dir


def register(subparsers: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    pool = subparsers.add_parser(
        "pool",
        help="sample behaviours from a policy and prepare their clips, distances and tree",
    )
    pool.add_argument("--env", required=True, help="GridWorld, Hopper, ... or a Gymnasium id")
    pool.add_argument(
        "--policy",
        default="random",
        help='"random" or a checkpoint directory (…/checkpoints/round-NNNN)',
    )
    pool.add_argument("--n", type=positive_int, default=200, help="behaviours in the pool")
    pool.add_argument(
        "--length",
        type=positive_int,
        default=None,
        help="steps per behaviour (default: --seconds of simulated time)",
    )
    pool.add_argument(
        "--seconds",
        type=float,
        default=None,
        help="simulated seconds per behaviour, played at real speed (default: the env's, "
        "e.g. 1.5 for Hopper)",
    )
    pool.add_argument("--seed", type=non_negative_int, default=0, help="random seed")
    pool.add_argument("--out", type=Path, required=True, help="output directory")
    pool.add_argument(
        "--workers", type=non_negative_int, default=2, help="render processes (0: in-process)"
    )
    pool.add_argument("--size", type=positive_int, default=240, help="frame width and height")
    pool.add_argument("--preset", default="ultrafast", help="x264 preset of the clips")
    pool.add_argument(
        "--exploration",
        type=float,
        default=0.0,
        help="share of steps with random actions while sampling, in [0, 1)",
    )
    pool.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    pool.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from groupwise.clips.timing import env_clip_timing
    from groupwise.clips.video import VideoConfig
    from groupwise.pool.publish import PublishConfig, prepare_pool
    from groupwise.rl.policy_files import load_policy

    try:
        if args.length is not None and args.seconds is not None:
            raise ValueError("give --length or --seconds, not both")
        if not 0.0 <= args.exploration < 1.0:  # before the output directory is made
            raise ValueError(f"exploration must be in [0, 1), got {args.exploration}")
        timing = env_clip_timing(args.env, args.seconds, steps=args.length)
        cfg = PublishConfig(
            env=args.env,
            width=args.size,
            height=args.size,
            workers=args.workers,
            video=VideoConfig(preset=args.preset),
            clips="eager",  # no server renders them later: the directory is the product
        )
        policy = load_policy(args.policy, args.env)
    except (ValueError, OSError) as error:
        raise UsageError(str(error)) from None
    out = writable_dir(args.out)
    rng = np.random.default_rng(args.seed)
    try:
        pool = prepare_pool(
            cfg,
            policy,
            rng,
            out,
            size=args.n,
            length=timing.steps,
            exploration_fraction=args.exploration,
            metadata={"policy": args.policy, "seed": args.seed},
            show_progress=not args.quiet,
        )
    except ValueError as error:  # e.g. an env without a fixed horizon
        raise UsageError(str(error)) from None
    t = pool.timings
    clip = pool.timing
    print(
        f"{len(pool.fragments)} behaviours of {clip.steps} steps ({clip.seconds:.2f} s, "
        f"clips of {clip.frames} frames at {clip.fps:.4g} fps: real speed), "
        f"{len(pool.candidates)} group candidates, in {t.total_s:.1f} s "
        f"(sample {t.sample_s:.1f}, clips {t.clips_s:.1f}, write {t.write_s:.1f})\n"
        f"pool: {out}\nclips: {pool.store.root}"
    )
    return 0
