"""SB3 callbacks: the extension point for progress reporting."""

from collections.abc import Callable

from stable_baselines3.common.callbacks import BaseCallback

ProgressFn = Callable[[int, int], None]
"""(steps done, steps total) -> None: a run's `RunCallback.on_phase("ppo", …)`."""


class ProgressCallback(BaseCallback):
    """Reports PPO progress to a `ProgressFn` once per rollout (and at the start)."""

    def __init__(self, total: int, report: ProgressFn | None = None) -> None:
        super().__init__()
        self.total = total
        self.report = report
        self._start = 0

    def _on_training_start(self) -> None:
        self._start = self.num_timesteps
        if self.report is not None:
            self.report(0, self.total)

    def _on_rollout_end(self) -> None:
        if self.report is not None:
            self.report(min(self.num_timesteps - self._start, self.total), self.total)

    def _on_step(self) -> bool:
        return True
