"""Argument types and the one-line error every subcommand reports bad input with."""

import argparse
import dataclasses
import json
import os
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

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


def add_config_argument(parser: argparse.ArgumentParser, below: str = "") -> None:
    """--config FILE: research settings as a JSON `RunConfig`, whole or partial (`read_config`)."""
    parser.add_argument(
        "--config",
        type=Path,
        metavar="FILE",
        help="research settings: a JSON config, whole (a run's config.json) or partial "
        '(e.g. {"reward": {"ensemble_size": 5}}), merged over the defaults' + below + "; the "
        "options given here win over it (its fields: groupwise.config)",
    )


def read_config(path: Path | None) -> dict[str, Any]:
    """The JSON object in `path` (a whole or partial `RunConfig`, `RunConfig.merged`); {}
    for None.

    Raises:
        UsageError: the file cannot be read or is not a JSON object.
    """
    if path is None:
        return {}
    try:
        data = json.loads(path.read_text())
    except OSError as error:
        raise UsageError(f"cannot read --config {path}: {error.strerror}") from None
    except ValueError as error:
        raise UsageError(f"--config {path} is not JSON: {error}") from None
    if not isinstance(data, dict):
        raise UsageError(f"--config {path} must hold a JSON object of config sections")
    return data


def config_error(error: ValueError) -> UsageError:
    """A config's validation error in one line: "config loop.rounds: Input should be
    greater than or equal to 1; …" (pydantic's own message spans lines)."""
    errors = getattr(error, "errors", None)
    if not callable(errors):
        return UsageError(str(error))
    parts = []
    for item in errors():
        where = ".".join(str(part) for part in item.get("loc", ()))
        parts.append(f"{where}: {item.get('msg', 'invalid')}" if where else item.get("msg", ""))
    return UsageError("config " + "; ".join(parts))


def add_training_arguments(parser: argparse.ArgumentParser) -> None:
    """--training, --teacher-error and --teacher-pace (`groupwise.run.continuous`)."""
    parser.add_argument(
        "--training",
        choices=("rounds", "continuous"),
        help="rounds: PPO trains after each round's feedback (default); continuous: PPO "
        "trains while a timed teacher answers, on a virtual clock",
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
    """--pool-size, --pool-variants and --pretrain-steps (`LoopConfig.pool_size`,
    `.pool_variants`, `TrainingConfig.pretrain_steps`): the app's pool settings."""
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
        "behaviours the policy rarely reaches (0: the policy alone; default: the recipe's)",
    )
    parser.add_argument(
        "--pretrain-steps",
        type=non_negative_int,
        metavar="N",
        help="PPO steps of unsupervised pre-training on a state-entropy bonus before round 0, "
        "so that the first pools are more diverse (PEBBLE; 0: none; default: the recipe's)",
    )


def add_recipe_arguments(parser: argparse.ArgumentParser) -> None:
    """--recipe and --ppo (`groupwise.recipes.RECIPES`, `PPO_PRESETS`): the recipe, and its PPO
    part on its own (its other parts: `add_pool_arguments`)."""
    from groupwise.recipes import DEFAULT_RECIPE, PPO_PRESETS, RECIPES

    parser.add_argument(
        "--recipe",
        choices=sorted(RECIPES),
        help="how to teach (recipes.RECIPES): "
        + "; ".join(f"{r.name}: {r.description}" for r in RECIPES.values()).replace("%", "%%")
        + f" (default {DEFAULT_RECIPE}); --pretrain-steps, --pool-variants, --ppo and "
        "--config change its parts",
    )
    parser.add_argument(
        "--ppo",
        choices=sorted(PPO_PRESETS),
        help="PPO settings (recipes.PPO_PRESETS): the study's (SPEC §3) or PPO's own MuJoCo "
        "settings (lr 3e-4, clip 0.2, γ 0.99, 64 × 64); default: the recipe's; --config's "
        "ppo fields change it",
    )


def with_recipe(cfg: "RunConfig", args: argparse.Namespace, env: str) -> "RunConfig":
    """`cfg` with --recipe's parts for `env` and --ppo's preset, when given."""
    from groupwise.recipes import DEFAULT_RECIPE, PPO_PRESETS, RECIPES

    cfg = RECIPES[args.recipe or DEFAULT_RECIPE].apply(cfg, env)
    return cfg if args.ppo is None else dataclasses.replace(cfg, ppo=PPO_PRESETS[args.ppo])


def pool_options(args: argparse.Namespace) -> dict[str, dict[str, Any]]:
    """The config sections --pool-size, --pool-variants and --pretrain-steps give (those
    given only), for `RunConfig.merged`."""
    loop = {"pool_size": args.pool_size, "pool_variants": args.pool_variants}
    options: dict[str, dict[str, Any]] = {"loop": {k: v for k, v in loop.items() if v is not None}}
    if args.pretrain_steps is not None:
        options["training"] = {"pretrain_steps": args.pretrain_steps}
    return options


def apply_teacher_options(
    cfg: "RunConfig", args: argparse.Namespace, target: str | None
) -> "RunConfig":
    """`cfg` with --training, --teacher-error and --teacher-pace applied; continuous
    training without a pace gets the paper's (`run.continuous.paper_pace`).

    Raises:
        ValueError: a teacher error outside (0, 0.5).
    """
    from groupwise.run.continuous import paper_pace

    mode = args.training or cfg.training.mode
    pace = args.teacher_pace or cfg.teacher.pace_s
    if mode == "continuous" and pace is None:  # the pairwise DMs: "pairwise", "pairwise-…"
        pace = paper_pace(target, pairwise=cfg.loop.decision_maker.startswith("pairwise"))
    error = args.teacher_error or cfg.teacher.label_error
    return dataclasses.replace(
        cfg,
        training=dataclasses.replace(cfg.training, mode=mode),
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
