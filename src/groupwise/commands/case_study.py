"""`groupwise case-study`: teach one of the paper's case-study behaviours to a simulated
decision-maker and measure it by the behaviour's target score (docs/case-studies.md)."""

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

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
from groupwise.envs import TARGETS

if TYPE_CHECKING:
    from groupwise.config import RunConfig


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not value > 0:
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {value}")
    return value


def _pair_budget(text: str) -> int | str:
    if text == "paper":
        return text
    return positive_int(text)


def pair_cap(pairs: int | str | None, target: str, comparisons: int) -> float | None:
    """`LoopConfig.pair_cap` for at most `pairs` preference pairs over a run of `comparisons`
    ("paper": the pairs of the paper's case study of `target`; None: no cap)."""
    from groupwise.run.continuous import PAPER_CASES

    if pairs is None:
        return None
    budget = PAPER_CASES[target][0] if pairs == "paper" else int(pairs)
    return budget / comparisons


CASE_DEFAULTS: dict[str, Any] = {
    "decision_maker": "groupwise",
    "comparisons": 1000,
    "rounds": 10,
    "eval_episodes": 0,  # the case study scores the target itself, after each round
}
"""A case study's `LoopConfig` fields where they differ from the study's defaults."""
CASE_STEPS_PER_ROUND = 100_000
"""A case study's PPO steps per round (`LoopConfig.steps` = this × its rounds)."""


def case_config(args: argparse.Namespace, partial: dict[str, Any]) -> "RunConfig":
    """The run config of a case study: the defaults with `CASE_DEFAULTS`, the target's env
    and clip length, the recipe --recipe (default "teach": among its parts a reward over the
    observation alone, as a target has no action cost and a clip shows states) and the PPO
    preset --ppo; then `partial` (--config) merged over it; then the options given.

    Raises:
        ValueError: `partial` names another env than the target's, or a field fails
            validation.
    """
    from groupwise.clips.timing import clip_timing, default_clip_seconds, env_step_seconds
    from groupwise.config import RunConfig

    target = TARGETS[args.target]
    loop_part = partial.get("loop")
    env = loop_part.get("env", target.env) if isinstance(loop_part, dict) else target.env
    if env != target.env:
        raise ValueError(f"{target.name} runs on {target.env}; leave loop.env out of --config")
    seconds = args.seconds or default_clip_seconds(target.base)
    base = RunConfig().merged(
        {
            "loop": {
                **CASE_DEFAULTS,
                "env": target.env,
                "steps": CASE_STEPS_PER_ROUND * CASE_DEFAULTS["rounds"],
                "fragment_length": clip_timing(env_step_seconds(target.env), seconds).steps,
            },
        }
    )
    cfg = with_recipe(base, args, target.env).merged(partial)
    loop = cfg.loop
    rounds = args.rounds or loop.rounds
    comparisons = args.preferences or loop.comparisons
    given = {
        "decision_maker": args.dm,
        "comparisons": comparisons,
        "rounds": rounds,
        "steps": (args.steps or _steps_per_round(partial, loop.steps, loop.rounds)) * rounds,
        "seed": args.seed,
        "pair_cap": pair_cap(args.pairs, target.name, comparisons),
    }
    if args.seconds is not None:
        given["fragment_length"] = clip_timing(env_step_seconds(target.env), seconds).steps
    options = pool_options(args)
    options["loop"] |= {k: v for k, v in given.items() if v is not None}
    return apply_teacher_options(cfg.merged(options), args, target.name)


def _steps_per_round(partial: dict[str, Any], steps: int, rounds: int) -> int:
    """PPO steps per round when --steps is not given: the config file's `loop.steps` over
    its rounds when it sets them, else `CASE_STEPS_PER_ROUND` (a file that sets only
    `loop.rounds` keeps a case study's steps per round)."""
    loop = partial.get("loop")
    if isinstance(loop, dict) and "steps" in loop:
        return steps // rounds
    return CASE_STEPS_PER_ROUND


def register(subparsers: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    case = subparsers.add_parser(
        "case-study",
        help="teach a case-study behaviour without a reward (backflip, stand-up, splits)",
        description=(
            "Run the RLHF loop on a reward-free target env with a simulated decision-maker "
            "who perceives the target score; write per round the preferences so far, the "
            "greedy policy's target score and success rate, the label error and the phase "
            "times (case-study.csv), then a video and a five-frame strip of the best final "
            "episode."
        ),
    )
    case.add_argument("--target", required=True, choices=sorted(TARGETS), help="the behaviour")
    case.add_argument(
        "--dm",
        help="simulated decision-maker (DECISION_MAKERS; default "
        f"{CASE_DEFAULTS['decision_maker']})",
    )
    case.add_argument(
        "--preferences",
        type=positive_int,
        help="total comparisons over the rounds (a group comparison gives several pairs; "
        f"default {CASE_DEFAULTS['comparisons']})",
    )
    case.add_argument(
        "--pairs",
        type=_pair_budget,
        metavar="P|paper",
        help="at most P preference pairs over the run ('paper': the pairs the paper's person "
        "gave for this target): each round keeps at most ⌊P / comparisons × its comparisons⌋ "
        "of its pairs (LoopConfig.pair_cap; default: every pair)",
    )
    case.add_argument(
        "--rounds",
        type=positive_int,
        help=f"feedback rounds (default {CASE_DEFAULTS['rounds']})",
    )
    case.add_argument(
        "--steps",
        type=positive_int,
        help=f"PPO steps per round (default {CASE_STEPS_PER_ROUND:,})",
    )
    case.add_argument(
        "--seconds",
        type=_positive_float,
        help="simulated seconds per behaviour (default: the env's clip duration)",
    )
    case.add_argument(
        "--eval-episodes", type=positive_int, default=5, help="episodes scored after each round"
    )
    case.add_argument("--seed", type=non_negative_int, help="random seed (default 0)")
    case.add_argument("--out", type=Path, required=True, help="output directory")
    case.add_argument("--no-video", action="store_true", help="skip the video and the strip")
    add_training_arguments(case)
    add_recipe_arguments(case)
    add_pool_arguments(case)
    add_config_argument(case, " of a case study (CASE_DEFAULTS, the target's env and clip)")
    add_takeaway_arguments(case)
    case.add_argument("-q", "--quiet", action="store_true", help="no progress bars")
    case.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from groupwise.agent_file.summary import AGENT_ZIP
    from groupwise.run.takeaway import TakeawayConfig
    from groupwise.study.case_studies.case_study import (
        CASE_FILE,
        STRIP_FILE,
        VIDEO_FILE,
        run_case_study,
    )
    from groupwise.teachers import DECISION_MAKERS

    target = TARGETS[args.target]
    try:
        cfg = case_config(args, read_config(args.config))
    except ValueError as error:
        raise config_error(error) from None
    if (dm := cfg.loop.decision_maker) not in DECISION_MAKERS:
        raise UsageError(f"unknown decision-maker {dm!r}; choose from {', '.join(DECISION_MAKERS)}")
    if cfg.loop.pair_cap is not None and cfg.training.mode == "continuous":
        raise UsageError("--pairs caps each round's pairs: use it with --training rounds")
    out = writable_dir(args.out)
    study = run_case_study(
        cfg,
        target,
        out,
        eval_episodes=args.eval_episodes,
        film=not args.no_video,
        show_progress=not args.quiet,
        takeaway=TakeawayConfig(by=args.takeaway, episodes=args.takeaway_episodes),
    )
    last = study.records[-1]
    chosen = study.records[study.choice.round]
    kept = (
        f"{study.choice.describe()}: target score {chosen.target_score_mean:.2f} "
        f"± {chosen.target_score_std:.2f}, success {chosen.success_rate:.0%} → {out / AGENT_ZIP}\n"
    )
    films = ""
    if study.filmed is not None:
        films = f"\nvideo: {out / VIDEO_FILE}, strip: {out / STRIP_FILE}"
    print(
        f"{target.name}: {last.pairs_total} preference pairs from {last.comparisons_total} "
        f"comparisons in {last.wall_s:.0f} s; target score {last.target_score_mean:.2f} "
        f"± {last.target_score_std:.2f} {target.unit} (success ≥ {target.threshold:g}: "
        f"{last.success_rate:.0%}, stretch ≥ {target.stretch:g}: {last.stretch_rate:.0%})\n"
        f"{kept}per round: {out / CASE_FILE}{films}"
    )
    return 0
