"""The study's reference: PPO on the env's own reward at a cell's step budget, no teacher.

A study cell teaches PPO through a learned reward; PPO given the env's reward itself, with
the same PPO settings, the same steps and the same greedy evaluation, is what a perfect
teacher and a perfect reward model would at best give at that budget (issue 42's DMC table
reports each cell beside it).
"""

import csv
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

from groupwise.config import RunConfig
from groupwise.envs import make_env
from groupwise.rl.ppo import PPOAgent
from groupwise.rl.rollout import evaluate
from groupwise.run.streams import eval_rng

REFERENCE_FILE = "reference.csv"


@dataclass(frozen=True)
class ReferencePoint:
    """The greedy policy after `steps` PPO steps on the env's reward."""

    env: str
    seed: int
    steps: int
    true_return_mean: float
    true_return_std: float


def train_on_true_reward(config: RunConfig, every: int) -> list[ReferencePoint]:
    """PPO with `config.ppo` on `config.loop.env`'s own reward for the cell's whole budget
    (`loop.steps` + `loop.final_steps`), its greedy policy evaluated on `loop.eval_episodes`
    episodes after every `every` steps (whole rollouts) and at the end."""
    loop = config.loop
    total = loop.steps + loop.final_steps
    if every < 1 or total < 1:
        raise ValueError(f"need a budget and every >= 1, got {total} steps and every {every}")
    agent = PPOAgent(lambda: make_env(loop.env), config.ppo, loop.seed)
    points: list[ReferencePoint] = []
    try:
        while agent.num_timesteps < total:
            agent.learn(min(every, total - agent.num_timesteps), loop.seed if not points else None)
            returns = evaluate(
                lambda: make_env(loop.env),
                agent.policy(deterministic=True),
                loop.eval_episodes,
                eval_rng(loop.seed),  # the episodes a cell's rounds are evaluated on
            )
            points.append(
                ReferencePoint(
                    loop.env,
                    loop.seed,
                    agent.num_timesteps,
                    float(returns.mean()),
                    float(returns.std()),
                )
            )
    finally:
        agent.close()
    return points


def write_points(points: Sequence[ReferencePoint], path: Path) -> None:
    """`points` as a CSV at `path` (one row each, `ReferencePoint`'s fields as columns)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(ReferencePoint.__dataclass_fields__))
        writer.writeheader()
        writer.writerows(asdict(p) for p in points)
