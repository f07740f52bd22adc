"""How a run tells what it is doing: one callback interface, as Stable-Baselines3's.

A `RunCallback` hears each phase of a round as it advances (`on_phase`: "sample",
"feedback", "reward", "ppo", "eval", "video", "package"; "pretrain" before round 0; with
done / total in the phase's own unit: PPO steps, pairs, episodes) and each finished round
(`on_round_end`). The CLI shows `ProgressBars`; the app's worker writes the phases to the
session row (`groupwise.worker.progress`); the study and the case studies hear finished
rounds.
"""

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, ClassVar

from tqdm.auto import tqdm

if TYPE_CHECKING:
    from groupwise.run.records import RoundRecord


class RunCallback:
    """Hears a run's progress; override what you need (each default does nothing)."""

    def on_phase(self, phase: str, done: int, total: int) -> None:
        """Phase `phase` of the current round is at `done` of `total`."""

    def on_round_end(self, record: "RoundRecord") -> None:
        """A round ended and was committed (its checkpoint written when the run has a
        directory)."""


class CallbackList(RunCallback):
    """Several callbacks, each told everything in order."""

    def __init__(self, callbacks: Sequence[RunCallback]) -> None:
        self.callbacks = list(callbacks)

    def on_phase(self, phase: str, done: int, total: int) -> None:
        for callback in self.callbacks:
            callback.on_phase(phase, done, total)

    def on_round_end(self, record: "RoundRecord") -> None:
        for callback in self.callbacks:
            callback.on_round_end(record)


class OnRoundEnd(RunCallback):
    """A function called with each finished round's record."""

    def __init__(self, function: Callable[["RoundRecord"], None]) -> None:
        self.function = function

    def on_round_end(self, record: "RoundRecord") -> None:
        self.function(record)


class ProgressBars(RunCallback):
    """tqdm bars: the rounds of a run, each round's PPO steps, and the rounds' policies the
    take-away choice (`groupwise.run.takeaway`) samples."""

    _BARS: ClassVar[dict[str, str]] = {
        "ppo": "step",
        "pretrain": "step",
        "takeaway": "round",
    }

    def __init__(self, rounds: int, done: int = 0, desc: str = "rounds") -> None:
        self._rounds = tqdm(total=rounds, initial=done, desc=desc, unit="round")
        self._ppo: tqdm | None = None

    def on_phase(self, phase: str, done: int, total: int) -> None:
        if phase not in self._BARS:
            return
        if self._ppo is None:
            self._ppo = tqdm(total=total, desc=phase, unit=self._BARS[phase], leave=False)
        self._ppo.n = done
        self._ppo.refresh()
        if done >= total:
            self._ppo.close()
            self._ppo = None

    def on_round_end(self, record: "RoundRecord") -> None:
        self._rounds.update(1)
        self._rounds.set_postfix(true_return=f"{record.true_return_mean:.1f}")

    def close(self) -> None:
        if self._ppo is not None:
            self._ppo.close()
        self._rounds.close()


def as_callback(callback: RunCallback | None) -> RunCallback:
    """`callback`, or one that does nothing."""
    return callback if callback is not None else RunCallback()
