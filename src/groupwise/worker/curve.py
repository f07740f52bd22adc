"""The learning curve of a continuous round, as the worker measures it.

Every trained round adds a point from its record (`storage.training.round_point`); a
continuous round also adds one after each refit (`worker.continuous_round`) and one for each
evaluation of the greedy policy's true return. An evaluation takes a snapshot of the policy
(`PPOAgent.snapshot`) between two PPO slices and runs in a process of its own (`Evaluator`),
which stores the point as of the snapshot, while PPO trains on: evaluating in the worker
took a tenth of its PPO time (`benchmarks/continuous.py`, issue 24). The first snapshot is
taken before the round's first rollout, the next ones once the previous evaluation has
finished and the slices have trained `EVAL_MIN_S` seconds since it was taken, or `EVAL_COST`
times as long as it took when that is longer: evaluations take at most about a tenth of the
evaluating core, and a tiny env still shows its curve within seconds.
"""

import time
from concurrent.futures import Future
from dataclasses import dataclass
from datetime import datetime
from typing import TYPE_CHECKING

import numpy as np

from groupwise.rl.policy import Policy
from groupwise.rl.rollout import EnvFactory, evaluate
from groupwise.run.run import Run
from groupwise.run.streams import eval_rng
from groupwise.storage.models import utcnow
from groupwise.storage.training import add_point
from groupwise.worker.background import BackgroundProcess, process_db

if TYPE_CHECKING:
    from groupwise.rl.ppo import PolicySnapshot

EVAL_MIN_S = 5.0
"""Least seconds of continuous training between two evaluations of the greedy policy."""
EVAL_COST = 10.0
"""Seconds of training between evaluations, per second the last evaluation took."""


def pool_steps(run: Run) -> int:
    """PPO steps of the policy that sampled the run's next round's pool (the last committed
    round's, 0 before the first)."""
    return run.records[-1].env_steps if run.records else 0


def true_return(make_env: EnvFactory, policy: Policy, episodes: int, seed: int) -> float:
    """`policy`'s mean true return over `episodes` episodes, the same ones as the rounds'
    evaluations (`eval_rng`)."""
    return float(np.mean(evaluate(make_env, policy, episodes, eval_rng(seed))))


@dataclass(frozen=True)
class CurvePoint:
    """A point of a session's learning curve, with the policy to evaluate for it."""

    session_id: str
    round_index: int
    ppo_steps: int
    pairs: int
    reward_val_accuracy: float | None
    pool_steps: int
    at: datetime
    env: str
    episodes: int
    seed: int
    policy: "PolicySnapshot"


def snapshot(
    session_id: str, round_index: int, run: Run, val_accuracy: float | None, pool: int
) -> CurvePoint:
    """The run's curve point now, with a greedy snapshot of its policy."""
    loop = run.cfg.loop
    return CurvePoint(
        session_id=session_id,
        round_index=round_index,
        ppo_steps=run.agent.num_timesteps,
        pairs=len(run.dataset),
        reward_val_accuracy=val_accuracy,
        pool_steps=pool,
        at=utcnow(),
        env=loop.env,
        episodes=loop.eval_episodes,
        seed=loop.seed,
        policy=run.ppo.snapshot(deterministic=True),
    )


class Evaluator:
    """One process that evaluates curve points and stores them (module docstring)."""

    def __init__(self, database_url: str) -> None:
        self._process = BackgroundProcess(database_url)
        self._process.submit(_warm_up)  # its start and imports now, not with the first point

    def submit(self, point: CurvePoint) -> "Future[float]":
        """Evaluate and store `point`; the future's result is the seconds it took."""
        return self._process.submit(_evaluate, point)

    def close(self) -> None:
        self._process.close()


def _warm_up() -> None:
    import groupwise.envs  # noqa: F401


def _evaluate(point: CurvePoint) -> float:
    from groupwise.envs import make_env

    tick = time.perf_counter()
    value = true_return(lambda: make_env(point.env), point.policy, point.episodes, point.seed)
    with process_db().write() as s:
        add_point(
            s,
            point.session_id,
            round_index=point.round_index,
            ppo_steps=point.ppo_steps,
            true_return=value,
            pairs=point.pairs,
            reward_val_accuracy=point.reward_val_accuracy,
            pool_steps=point.pool_steps,
            now=point.at,
        )
    return time.perf_counter() - tick
