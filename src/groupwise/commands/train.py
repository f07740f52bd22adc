"""`groupwise train`: a headless RLHF session with a simulated decision-maker, or the
continuation of an app session (`--from-session DIR`)."""

import argparse
import math
from pathlib import Path

from groupwise.commands.arguments import (
    UsageError,
    add_config_argument,
    add_pool_arguments,
    add_recipe_arguments,
    add_takeaway_arguments,
    add_training_arguments,
    apply_teacher_options,
    config_error,
    non_negative_int,
    pool_options,
    positive_int,
    read_config,
    with_recipe,
    writable_dir,
)

FROM_SESSION_EXCLUDES = (
    "env",
    "config",
    "out",
    "final_steps",
    "seed",
    "training",
    "teacher_pace",
    "teacher_error",
    "pretrain_steps",
    "pool_size",
    "pool_variants",
    "recipe",
    "ppo",
)
"""Options --from-session takes from DIR itself (its config.json)."""


def register(subparsers: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    train = subparsers.add_parser(
        "train",
        help="run a headless RLHF session with a simulated decision-maker, or continue an "
        "app session (--from-session)",
    )
    train.add_argument("--env", help="GridWorld, Hopper, ... or a Gymnasium id")
    train.add_argument(
        "--dm",
        dest="dm",
        help="simulated decision-maker (default pairwise; with --from-session it answers "
        "the extra --rounds)",
    )
    train.add_argument("--comparisons", type=positive_int, help="total comparisons")
    train.add_argument(
        "--rounds", type=positive_int, help="feedback rounds (--from-session: more rounds)"
    )
    train.add_argument(
        "--steps",
        type=non_negative_int,
        help="total PPO steps over the rounds (--from-session: more PPO steps on the frozen "
        "learned reward)",
    )
    train.add_argument(
        "--final-steps",
        type=non_negative_int,
        help="PPO steps on the frozen learned reward after the last round",
    )
    train.add_argument("--seed", type=non_negative_int, help="random seed")
    add_config_argument(train)
    train.add_argument("--out", type=Path, help="output directory (not with --from-session)")
    train.add_argument(
        "--resume", action="store_true", help="continue from the last checkpoint in --out"
    )
    train.add_argument(
        "--from-session",
        type=Path,
        metavar="DIR",
        help="continue an app session's directory (DATA/sessions/s-…) or a train output in "
        "place, from its latest checkpoint: --steps N or --rounds N --dm NAME",
    )
    add_training_arguments(train)
    add_recipe_arguments(train)
    add_pool_arguments(train)
    add_takeaway_arguments(train)
    train.add_argument("-q", "--quiet", action="store_true", help="no progress bars")
    train.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    if args.from_session is not None:
        return _from_session(args)
    from groupwise.agent_file.summary import AGENT_ZIP
    from groupwise.config import RunConfig
    from groupwise.envs import make_env
    from groupwise.run.headless import run_session
    from groupwise.run.run import RESULTS_FILE, ConfigMismatchError
    from groupwise.run.takeaway import TakeawayConfig, read_choice
    from groupwise.teachers import DECISION_MAKERS

    if args.env is None or args.out is None:
        raise UsageError("train needs --env and --out (or --from-session DIR)")
    dm = args.dm or "pairwise"
    if dm not in DECISION_MAKERS:
        raise UsageError(f"unknown decision-maker {dm!r}; choose from {', '.join(DECISION_MAKERS)}")
    overrides = {
        "env": args.env,
        "decision_maker": dm,
        "comparisons": args.comparisons,
        "rounds": args.rounds,
        "steps": args.steps,
        "seed": args.seed,
        "final_steps": args.final_steps,
    }
    given = pool_options(args)
    given["loop"] |= {key: value for key, value in overrides.items() if value is not None}
    try:
        make_env(args.env).close()  # the registry's message names the known envs
        base = with_recipe(RunConfig(), args, args.env).merged(read_config(args.config))
        cfg = apply_teacher_options(base.merged(given), args, None)
    except ValueError as error:
        raise config_error(error) from None
    except OSError as error:
        raise UsageError(str(error)) from None
    out = writable_dir(args.out)
    try:
        takeaway = TakeawayConfig(by=args.takeaway, episodes=args.takeaway_episodes)
        records = run_session(
            cfg, out, resume=args.resume, show_progress=not args.quiet, takeaway=takeaway
        )
    except ConfigMismatchError as error:
        raise UsageError(str(error)) from None
    last = records[-1]
    choice = read_choice(out)
    print(
        f"{len(records)} rounds, {last.pairs_total} preference pairs, "
        f"true return {last.true_return_mean:.2f} ± {last.true_return_std:.2f}\n"
        + ("" if choice is None else f"{choice.describe()}: {out / AGENT_ZIP}\n")
        + f"results: {out / RESULTS_FILE}\ncheckpoints: {out / 'checkpoints'}\n"
        f"tensorboard: tensorboard --logdir {out / 'tb'}"
    )
    return 0


def _from_session(args: argparse.Namespace) -> int:
    """More PPO steps on the frozen reward, or more rounds by a simulated DM (docs/app.md)."""
    from groupwise.agent_file.summary import AGENT_VIDEO, AGENT_ZIP
    from groupwise.run.final import continue_run
    from groupwise.run.run import CONFIG_FILE, RESULTS_FILE

    given = [
        f"--{name.replace('_', '-')}"
        for name in FROM_SESSION_EXCLUDES
        if getattr(args, name) is not None
    ]
    if given or args.resume:
        raise UsageError(
            f"--from-session continues DIR with its own config.json, in place; leave out "
            f"{', '.join(given or ['--resume'])}"
        )
    if (args.steps is None) == (args.rounds is None):
        raise UsageError("--from-session needs either --steps N or --rounds N")
    if args.steps == 0:
        raise UsageError("--steps must be at least 1")
    if args.rounds is not None and args.dm is None:
        raise UsageError(
            "--rounds needs --dm NAME: nobody answers a headless round but a simulated "
            "decision-maker"
        )
    directory = args.from_session
    if not (directory / CONFIG_FILE).is_file():
        raise UsageError(f"{directory} is not a session directory: it has no {CONFIG_FILE}")
    writable_dir(directory)
    per_round = None
    if args.comparisons is not None and args.rounds is not None:
        per_round = math.ceil(args.comparisons / args.rounds)
    try:
        records = continue_run(
            directory,
            steps=args.steps,
            rounds=args.rounds,
            decision_maker=args.dm,
            comparisons=per_round,
            show_progress=not args.quiet,
        )
    except (ValueError, FileNotFoundError) as error:
        raise UsageError(str(error)) from None
    last = records[-1]
    print(
        f"round {last.round}: {last.env_steps:,} PPO steps in all, "
        f"true return {last.true_return_mean:.2f} ± {last.true_return_std:.2f}\n"
        f"results: {directory / RESULTS_FILE}\nagent: {directory / AGENT_ZIP} "
        f"(groupwise.load_agent), video: {directory / AGENT_VIDEO}"
    )
    return 0
