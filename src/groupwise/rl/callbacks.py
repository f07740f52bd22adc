"""SB3 callbacks: the extension point for progress reporting."""

import math
from collections.abc import Callable
from typing import Any

from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.on_policy_algorithm import OnPolicyAlgorithm

from groupwise.types import ProgressFn

__all__ = ["ProgressCallback", "ProgressFn", "planned_steps"]


def planned_steps(model: Any, steps: int) -> int:
    """The env steps `model.learn(total_timesteps=steps)` runs: an on-policy algorithm
    (PPO, A2C) collects whole rollouts of n_envs × n_steps, so `steps` rounded up to whole
    rollouts (1 step asked of a 2,048-step rollout runs 2,048); any other model, `steps`."""
    if isinstance(model, OnPolicyAlgorithm):
        rollout = model.n_envs * model.n_steps
        return math.ceil(steps / rollout) * rollout
    return steps


class ProgressCallback(BaseCallback):
    """Reports training progress to a `ProgressFn` once per rollout (and at the start).

    The total reported is what runs (`planned_steps`: whole rollouts for PPO), not the
    `total` asked, so the count ends at the total (issue 23: "PPO 1 / 1 steps" while 2,048
    ran).

    `stop`, when given, is asked at every step of a rollout (each vec-env step): once it
    says True the rollout in progress ends there and `learn` returns without training on it
    (SB3's own way: `_on_step` returning False); `rollouts` counts the rollouts collected
    whole (issue 39: a continuous round's End round waits for no PPO slice)."""

    def __init__(
        self,
        total: int,
        report: ProgressFn | None = None,
        stop: Callable[[], bool] | None = None,
    ) -> None:
        super().__init__()
        self.asked = total
        self.total = total
        self.report = report
        self.stop = stop
        self.stopped = False
        self.rollouts = 0
        self._start = 0

    def _on_training_start(self) -> None:
        self._start = self.num_timesteps
        self.total = planned_steps(self.model, self.asked)
        if self.report is not None:
            self.report(0, self.total)

    def _on_rollout_end(self) -> None:
        self.rollouts += 1
        if self.report is not None:
            self.report(min(self.num_timesteps - self._start, self.total), self.total)

    def _on_step(self) -> bool:
        if self.stop is not None and self.stop():
            self.stopped = True
        return not self.stopped
