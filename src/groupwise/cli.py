"""The `groupwise` command line: a thin shell that parses, validates and calls the core."""

import argparse
import dataclasses
import logging
import os
import sys
from collections.abc import Callable, Sequence
from pathlib import Path

log = logging.getLogger("groupwise")


class UsageError(Exception):
    """A problem with what the user asked for: reported in one line, exit code 2."""


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a number >= 1, got {value}")
    return value


def _non_negative_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {value}")
    return value


def _writable_dir(path: Path) -> Path:
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise UsageError(f"cannot create output directory {path}: {error.strerror}") from None
    if not os.access(path, os.W_OK | os.X_OK):
        raise UsageError(f"output directory {path} is not writable")
    return path


def _train(args: argparse.Namespace) -> int:
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
    out = _writable_dir(args.out)
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


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="groupwise",
        description="RLHF with interactive groupwise comparison of agent behaviours.",
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log debug detail")
    commands = parser.add_subparsers(dest="command", required=True)

    train = commands.add_parser(
        "train", help="run a headless RLHF session with a simulated decision-maker"
    )
    train.add_argument("--env", required=True, help="GridWorld, Hopper, ... or a Gymnasium id")
    train.add_argument("--oracle", default="pairwise", help="simulated decision-maker")
    train.add_argument("--comparisons", type=_positive_int, help="total comparisons")
    train.add_argument("--rounds", type=_positive_int, help="feedback rounds")
    train.add_argument("--steps", type=_non_negative_int, help="total PPO steps over the rounds")
    train.add_argument("--final-steps", type=_non_negative_int,
                       help="PPO steps on the frozen learned reward after the last round")
    train.add_argument("--seed", type=_non_negative_int, help="random seed")
    train.add_argument("--config", type=Path, help="JSON config (as written by a previous run)")
    train.add_argument("--out", type=Path, required=True, help="output directory")
    train.add_argument("--resume", action="store_true",
                       help="continue from the last checkpoint in --out")
    train.add_argument("-q", "--quiet", action="store_true", help="no progress bars")
    train.set_defaults(handler=_train)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.DEBUG if args.verbose else logging.INFO,
        format="%(asctime)s %(levelname)s %(name)s: %(message)s",
    )
    handler: Callable[[argparse.Namespace], int] = args.handler
    try:
        return handler(args)
    except UsageError as error:
        print(f"groupwise: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("groupwise: interrupted; continue with --resume", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
