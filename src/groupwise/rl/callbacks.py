"""SB3 callbacks: the extension point for progress reporting."""

from collections.abc import Callable

from stable_baselines3.common.callbacks import BaseCallback
from tqdm.auto import tqdm

ProgressFn = Callable[[int, int], None]
"""(steps done, steps total) -> None; the server's worker reports progress through this."""


class ProgressCallback(BaseCallback):
    """Reports PPO progress to a tqdm bar and/or a `ProgressFn`, once per rollout."""

    def __init__(self, total: int, show_bar: bool, report: ProgressFn | None = None) -> None:
        super().__init__()
        self.total = total
        self.show_bar = show_bar
        self.report = report
        self._bar: tqdm | None = None
        self._start = 0

    def _on_training_start(self) -> None:
        self._start = self.num_timesteps
        if self.show_bar:
            self._bar = tqdm(total=self.total, desc="ppo", unit="step", leave=False)

    def _on_rollout_end(self) -> None:
        done = min(self.num_timesteps - self._start, self.total)
        if self._bar is not None:
            self._bar.n = done
            self._bar.refresh()
        if self.report is not None:
            self.report(done, self.total)

    def _on_step(self) -> bool:
        return True

    def _on_training_end(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None
