"""`groupwise case-study`: teach one of the paper's case-study behaviours to a simulated
decision-maker and measure it by the behaviour's target score (docs/case-studies.md)."""

import argparse
import dataclasses
from pathlib import Path

from groupwise.commands.arguments import (
    UsageError,
    add_pool_arguments,
    add_takeaway_arguments,
    add_training_arguments,
    apply_teacher_options,
    non_negative_int,
    positive_int,
    writable_dir,
)
from groupwise.config import PPO_PRESETS
from groupwise.envs import TARGETS


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
    case.add_argument("--dm", default="groupwise", help="simulated decision-maker (ORACLES)")
    case.add_argument(
        "--preferences",
        type=positive_int,
        default=1000,
        help="total comparisons over the rounds (a group comparison gives several pairs)",
    )
    case.add_argument(
        "--pairs",
        type=_pair_budget,
        metavar="P|paper",
        help="at most P preference pairs over the run ('paper': the pairs the paper's person "
        "gave for this target): each round keeps at most ⌊P / comparisons × its comparisons⌋ "
        "of its pairs (LoopConfig.pair_cap; default: every pair)",
    )
    case.add_argument("--rounds", type=positive_int, default=10, help="feedback rounds")
    case.add_argument("--steps", type=positive_int, default=100_000, help="PPO steps per round")
    case.add_argument(
        "--seconds",
        type=_positive_float,
        help="simulated seconds per behaviour (default: the env's clip duration)",
    )
    case.add_argument(
        "--reward-inputs",
        choices=("obs", "obs-act"),
        default="obs",
        help="what the reward members see: the observation alone (default: a target has no "
        "action cost, and a clip shows states) or [obs ; act] as in the study",
    )
    case.add_argument(
        "--ppo",
        choices=sorted(PPO_PRESETS),
        default="study",
        help="PPO settings (config.PPO_PRESETS): the study's (SPEC §3) or PPO's own MuJoCo "
        "settings (lr 3e-4, clip 0.2, γ 0.99, 64 × 64)",
    )
    case.add_argument(
        "--eval-episodes", type=positive_int, default=5, help="episodes scored after each round"
    )
    case.add_argument("--seed", type=non_negative_int, default=0, help="random seed")
    case.add_argument("--out", type=Path, required=True, help="output directory")
    case.add_argument("--no-video", action="store_true", help="skip the video and the strip")
    add_training_arguments(case)
    add_pool_arguments(case)
    case.add_argument(
        "--pretrain-steps",
        type=non_negative_int,
        default=0,
        metavar="N",
        help="PPO steps of unsupervised pre-training on a state-entropy bonus before round 0, "
        "so that the first pools are more diverse (PEBBLE; default 0: none)",
    )
    add_takeaway_arguments(case)
    case.add_argument("-q", "--quiet", action="store_true", help="no progress bars")
    case.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from groupwise.clips.timing import clip_timing, default_clip_seconds, env_step_seconds
    from groupwise.config import LoopConfig, RunConfig
    from groupwise.oracles import ORACLES
    from groupwise.agent_file.summary import AGENT_ZIP
    from groupwise.run.takeaway import TakeawayConfig
    from groupwise.study.case_study import CASE_FILE, STRIP_FILE, VIDEO_FILE, run_case_study

    if args.dm not in ORACLES:
        raise UsageError(f"unknown decision-maker {args.dm!r}; choose from {', '.join(ORACLES)}")
    target = TARGETS[args.target]
    seconds = args.seconds or default_clip_seconds(target.base)
    length = clip_timing(env_step_seconds(target.env), seconds).steps
    try:
        base = RunConfig()
        loop = LoopConfig(
            **{
                **dataclasses.asdict(base.loop),
                "env": target.env,
                "oracle": args.dm,
                "comparisons": args.preferences,
                "rounds": args.rounds,
                "steps": args.steps * args.rounds,
                "fragment_length": length,
                "eval_episodes": 0,  # the case study scores the target itself
                "pair_cap": pair_cap(args.pairs, target.name, args.preferences),
                "seed": args.seed,
                "pool_size": args.pool_size,
                "pool_variants": args.pool_variants or 0,
                "pool_variants_greedy": bool(args.pool_variants_greedy),
                "pool_lookahead": args.pool_lookahead or 0,
                "adopt_variants": bool(args.adopt_variants),
                "suggestion_rank": args.suggestions or "variance",
            }
        )
        reward = dataclasses.replace(
            base.reward,
            use_actions=args.reward_inputs == "obs-act",
            exploration_bonus=args.reward_bonus or 0.0,
            pessimism=args.reward_pessimism or 0.0,
        )
        training = dataclasses.replace(base.training, pretrain_steps=args.pretrain_steps)
        cfg = apply_teacher_options(
            dataclasses.replace(
                base, loop=loop, reward=reward, training=training, ppo=PPO_PRESETS[args.ppo]
            ),
            args,
            target.name,
        )
    except ValueError as error:
        raise UsageError(str(error)) from None
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
