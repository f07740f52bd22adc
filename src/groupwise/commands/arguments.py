"""Argument types and the one-line error every subcommand reports bad input with."""

import argparse
import dataclasses
import os
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from groupwise.config import RunConfig


class UsageError(Exception):
    """A problem with what the user asked for: reported in one line, exit code 2."""


def int_at_least(minimum: int) -> Callable[[str], int]:
    """An argparse type: a whole number >= `minimum`, with a one-line message otherwise."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"expected a number >= {minimum}, got {value}")
        return value

    return parse


positive_int = int_at_least(1)
non_negative_int = int_at_least(0)


def _number(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None


def positive_float(text: str) -> float:
    """An argparse type: a number > 0, with a one-line message otherwise."""
    value = _number(text)
    if not 0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"expected a finite number > 0, got {text}")
    return value


def non_negative_float(text: str) -> float:
    """An argparse type: a finite number >= 0, with a one-line message otherwise."""
    value = _number(text)
    if not 0 <= value < float("inf"):
        raise argparse.ArgumentTypeError(f"expected a finite number >= 0, got {text}")
    return value


def writable_dir(path: Path) -> Path:
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise UsageError(f"cannot create output directory {path}: {error.strerror}") from None
    if not os.access(path, os.W_OK | os.X_OK):
        raise UsageError(f"output directory {path} is not writable")
    return path


def add_training_arguments(parser: argparse.ArgumentParser) -> None:
    """--training, --continue-from, --teacher-error and --teacher-pace
    (`groupwise.run.continuous`, `groupwise.run.keep`)."""
    parser.add_argument(
        "--training",
        choices=("rounds", "continuous"),
        help="rounds: PPO trains after each round's feedback (default); continuous: PPO "
        "trains while a timed teacher answers, on a virtual clock",
    )
    parser.add_argument(
        "--continue-from",
        choices=("last", "preferred"),
        help="which policy each round trains on from: the last round's (default), or the one "
        "the simulated teacher prefers so far (it compares the last round's greedy episodes "
        "with those of the policy that round began from)",
    )
    parser.add_argument(
        "--teacher-error",
        type=positive_float,
        metavar="E",
        help="a teacher calibrated to people: wrong on this share of behaviour pairs of "
        "unequal return (0.12: the paper's user study), its noise set per pool",
    )
    parser.add_argument(
        "--teacher-pace",
        type=positive_float,
        metavar="S",
        help="seconds of the virtual clock the simulated teacher takes per comparison "
        "(default with --training continuous: the paper's case studies' rate)",
    )


def add_pool_arguments(parser: argparse.ArgumentParser) -> None:
    """--pool-size, --pool-variants, --pool-variants-greedy, --pool-lookahead,
    --adopt-variants, --suggestions, --reward-pessimism and --reward-bonus
    (`LoopConfig.pool_size`, `.pool_variants`, `.pool_variants_greedy`, `.pool_lookahead`,
    `.adopt_variants`, `.suggestion_rank`, `RewardConfig.pessimism`, `.exploration_bonus`)."""
    parser.add_argument(
        "--pool-size",
        type=int_at_least(2),
        metavar="N",
        help="behaviours in every round's pool, as the app's pool size (default: twice the "
        "round's comparisons, at most 200)",
    )
    parser.add_argument(
        "--pool-variants",
        type=int_at_least(0),
        metavar="K",
        help="sample half of each pool's windows from K variants of the current policy, each "
        "pushing its actions one way (offsets drawn anew each round), so that the pools show "
        "behaviours the policy rarely reaches (default 0: the policy alone)",
    )
    parser.add_argument(
        "--pool-variants-greedy",
        action="store_true",
        default=None,
        help="with --pool-variants: the variants push the greedy policy (what the evaluation "
        "scores and the take-away agent does) and the first does not push, so the teacher "
        "sees what the agent actually does",
    )
    parser.add_argument(
        "--pool-lookahead",
        type=int_at_least(0),
        metavar="N",
        help="with --pool-variants: from the second round on, the variants are of the policy "
        "a copy of the agent reaches after N more PPO steps on the current learned reward, "
        "so the teacher judges where PPO is going (default 0: of the current policy)",
    )
    parser.add_argument(
        "--adopt-variants",
        action="store_true",
        default=None,
        help="with --pool-variants: when the teacher preferred one variant's behaviours to the "
        "policy's own in a round's comparisons, the policy takes that variant's push before "
        "PPO trains on (run.adopt)",
    )
    parser.add_argument(
        "--suggestions",
        choices=("variance", "optimistic"),
        help="the order of the group suggestions (the Groupwise-DM's queries): SPEC's "
        "group-variance score (default), or the most promising groups first, each against "
        "the partners the reward ensemble disputes most",
    )
    parser.add_argument(
        "--reward-pessimism",
        type=non_negative_float,
        metavar="K",
        help="PPO's reward subtracts K times the reward members' disagreement (their sd), "
        "every round, so the policy is paid less where the teacher has not judged (default 0)",
    )
    parser.add_argument(
        "--reward-bonus",
        type=non_negative_float,
        metavar="B",
        help="PPO's reward adds B times the reward members' disagreement (their sd), halved "
        "every round, so the policy seeks what the teacher has not judged yet (default 0)",
    )


def apply_teacher_options(
    cfg: "RunConfig", args: argparse.Namespace, target: str | None
) -> "RunConfig":
    """`cfg` with --training, --continue-from, --teacher-error and --teacher-pace applied;
    continuous training without a pace gets the paper's (`run.continuous.paper_pace`).

    Raises:
        ValueError: a teacher error outside (0, 0.5).
    """
    from groupwise.run.continuous import paper_pace

    mode = args.training or cfg.training.mode
    pace = args.teacher_pace or cfg.teacher.pace_s
    if mode == "continuous" and pace is None:  # the pairwise DMs: "pairwise", "pairwise-…"
        pace = paper_pace(target, pairwise=cfg.loop.oracle.startswith("pairwise"))
    error = args.teacher_error or cfg.teacher.label_error
    keep = args.continue_from or cfg.training.continue_from
    return dataclasses.replace(
        cfg,
        training=dataclasses.replace(cfg.training, mode=mode, continue_from=keep),
        teacher=dataclasses.replace(cfg.teacher, pace_s=pace, label_error=error),
    )


def add_takeaway_arguments(parser: argparse.ArgumentParser) -> None:
    """--takeaway and --takeaway-episodes (`groupwise.run.takeaway.TakeawayConfig`)."""
    parser.add_argument(
        "--takeaway",
        choices=("teacher", "last"),
        default="teacher",
        help="which round's policy the run hands over (agent.zip): the one the simulated "
        "teacher prefers when it compares every round's greedy episodes (default), or the last",
    )
    parser.add_argument(
        "--takeaway-episodes",
        type=int_at_least(1),
        default=3,
        help="greedy episodes of each round's policy the teacher compares (default 3)",
    )
