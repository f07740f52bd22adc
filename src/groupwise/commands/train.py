"""`groupwise train`: a headless RLHF session with a simulated decision-maker."""

import argparse
import dataclasses
from pathlib import Path

from groupwise.commands.arguments import UsageError, non_negative_int, positive_int, writable_dir


def register(subparsers: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    train = subparsers.add_parser(
        "train", help="run a headless RLHF session with a simulated decision-maker"
    )
    train.add_argument("--env", required=True, help="GridWorld, Hopper, ... or a Gymnasium id")
    train.add_argument("--oracle", default="pairwise", help="simulated decision-maker")
    train.add_argument("--comparisons", type=positive_int, help="total comparisons")
    train.add_argument("--rounds", type=positive_int, help="feedback rounds")
    train.add_argument("--steps", type=non_negative_int, help="total PPO steps over the rounds")
    train.add_argument(
        "--final-steps",
        type=non_negative_int,
        help="PPO steps on the frozen learned reward after the last round",
    )
    train.add_argument("--seed", type=non_negative_int, help="random seed")
    train.add_argument("--config", type=Path, help="JSON config (as written by a previous run)")
    train.add_argument("--out", type=Path, required=True, help="output directory")
    train.add_argument(
        "--resume", action="store_true", help="continue from the last checkpoint in --out"
    )
    train.add_argument("-q", "--quiet", action="store_true", help="no progress bars")
    train.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from groupwise.config import LoopConfig, RunConfig
    from groupwise.envs import make_env
    from groupwise.loop import RESULTS_FILE, ConfigMismatchError, run_session
    from groupwise.oracles import ORACLES

    if args.oracle not in ORACLES:
        raise UsageError(f"unknown oracle {args.oracle!r}; choose from {', '.join(ORACLES)}")
    overrides = {
        "env": args.env,
        "oracle": args.oracle,
        "comparisons": args.comparisons,
        "rounds": args.rounds,
        "steps": args.steps,
        "seed": args.seed,
        "final_steps": args.final_steps,
    }
    given = {key: value for key, value in overrides.items() if value is not None}
    try:
        make_env(args.env).close()  # the registry's message names the known envs
        base = RunConfig.load(args.config) if args.config else RunConfig()
        cfg = dataclasses.replace(
            base, loop=LoopConfig(**{**dataclasses.asdict(base.loop), **given})
        )
    except (ValueError, OSError) as error:
        raise UsageError(str(error)) from None
    out = writable_dir(args.out)
    try:
        records = run_session(cfg, out, resume=args.resume, show_progress=not args.quiet)
    except ConfigMismatchError as error:
        raise UsageError(str(error)) from None
    last = records[-1]
    print(
        f"{len(records)} rounds, {last.pairs_total} preference pairs, "
        f"true return {last.true_return_mean:.2f} ± {last.true_return_std:.2f}\n"
        f"results: {out / RESULTS_FILE}\ncheckpoints: {out / 'checkpoints'}\n"
        f"tensorboard: tensorboard --logdir {out / 'tb'}"
    )
    return 0
