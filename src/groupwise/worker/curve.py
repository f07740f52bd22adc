"""The learning curve of a continuous round, as the worker measures it.

Every trained round adds a point from its record (`storage.training.round_point`); a
continuous round also adds one after each refit and each evaluation of the greedy policy
(`worker.live`), which runs when the round's PPO slices have trained `EVAL_MIN_S` seconds
since the last one, or `EVAL_COST` times as long as that evaluation took when that is
longer: evaluation takes at most about a tenth of the training's time, and a tiny env still
shows its curve within seconds.
"""

import numpy as np

from groupwise.rl.rollout import evaluate
from groupwise.run.run import Run
from groupwise.run.streams import eval_rng

EVAL_MIN_S = 5.0
"""Least seconds of continuous training between two evaluations of the greedy policy."""
EVAL_COST = 10.0
"""Seconds of training between evaluations, per second the last evaluation took."""


def pool_steps(run: Run) -> int:
    """PPO steps of the policy that sampled the run's next round's pool (the last committed
    round's, 0 before the first)."""
    return run.records[-1].env_steps if run.records else 0


def true_return(run: Run) -> float | None:
    """The greedy policy's mean true return over `eval_episodes`, on the same episodes as
    the rounds' evaluations (`eval_rng`); None when `eval_episodes` is 0."""
    loop = run.cfg.loop
    if loop.eval_episodes == 0:
        return None
    policy = run.agent.policy(deterministic=True)
    returns = evaluate(run.make_env, policy, loop.eval_episodes, eval_rng(loop.seed))
    return float(np.mean(returns))
