"""The case studies' reference: PPO on the target's own step score, no teacher (issue 20).

A simulated teacher perceives a target's per-step score (`envs.targets`); the reward model
learns it from comparisons; PPO trains on that. PPO trained on the score itself, with the
same PPO settings and step budget, is what a perfect teacher and a perfect reward model
would at best give at that budget: where it does not reach the target's threshold, no
feedback will, and the budget is what stands in the way. After every `every` steps the
greedy policy is scored on the target as the case study scores it (`evaluate_target`).

    python -m groupwise.study.case_studies.target_reference --target walker-splits --steps 204800 \\
        --every 40960 --seeds 0 1 2 [--ppo study|mujoco] --out OUT
"""

import argparse
import csv
import logging
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, SupportsFloat

import gymnasium as gym
import numpy as np

from groupwise.config import PPOConfig
from groupwise.envs import TARGETS, Target, make_env
from groupwise.envs.targets import TARGET_SCORE_KEY
from groupwise.recipes import PPO_PRESETS
from groupwise.rl.ppo import PPOAgent
from groupwise.study.case_studies.target_evaluation import evaluate_target

log = logging.getLogger(__name__)

REFERENCE_FILE = "reference.csv"


class ScoreAsReward(gym.Wrapper[Any, Any, Any, Any]):
    """A target env whose reward is its step score (`TARGET_SCORE_KEY`), not 0."""

    def step(self, action: Any) -> tuple[Any, SupportsFloat, bool, bool, dict[str, Any]]:
        obs, _, terminated, truncated, info = self.env.step(action)
        return obs, float(info[TARGET_SCORE_KEY]), terminated, truncated, info


@dataclass(frozen=True)
class ReferencePoint:
    """The greedy policy after `steps` PPO steps on the score, scored on the target."""

    target: str
    seed: int
    steps: int
    target_score_mean: float
    target_score_std: float
    success_rate: float
    stretch_rate: float
    true_return_mean: float
    """Mean sum of the step scores: what PPO maximised."""


def train_on_score(
    target: Target,
    cfg: PPOConfig,
    steps: int,
    every: int,
    seed: int,
    eval_episodes: int = 5,
) -> list[ReferencePoint]:
    """PPO on `target`'s step score for `steps` steps, scored every `every` steps (whole
    rollouts) on `eval_episodes` greedy episodes (module docstring)."""
    if every < 1 or steps < 1:
        raise ValueError(f"need steps >= 1 and every >= 1, got {steps} and {every}")
    agent = PPOAgent(lambda: ScoreAsReward(make_env(target.env)), cfg, seed)
    rng = np.random.default_rng(seed)
    points: list[ReferencePoint] = []
    while agent.num_timesteps < steps:
        agent.learn(min(every, steps - agent.num_timesteps), seed if not points else None)
        evaluation = evaluate_target(
            lambda: make_env(target.env), agent.policy(deterministic=True), eval_episodes, rng
        )
        points.append(
            ReferencePoint(target.name, seed, agent.num_timesteps, **evaluation.summary(target))
        )
        log.info("%s seed %d: %s", target.name, seed, points[-1])
    return points


def write_points(points: Sequence[ReferencePoint], path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(asdict(points[0])))
        writer.writeheader()
        writer.writerows(asdict(p) for p in points)


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--target", choices=sorted(TARGETS), required=True)
    parser.add_argument("--steps", type=int, default=204_800, help="PPO steps")
    parser.add_argument("--every", type=int, default=40_960, help="steps between scorings")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--eval-episodes", type=int, default=5)
    parser.add_argument("--ppo", choices=sorted(PPO_PRESETS), default="study", help="PPO settings")
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    target = TARGETS[args.target]
    points = []
    for seed in args.seeds:
        points += train_on_score(
            target, PPO_PRESETS[args.ppo], args.steps, args.every, seed, args.eval_episodes
        )
        write_points(points, args.out / f"{target.name}-{args.ppo}-{REFERENCE_FILE}")
    for p in points:
        print(
            f"{p.target} seed {p.seed} steps {p.steps}: score {p.target_score_mean:.2f} ± "
            f"{p.target_score_std:.2f}, success {p.success_rate:.0%}, "
            f"return {p.true_return_mean:.1f}"
        )


if __name__ == "__main__":
    main()
