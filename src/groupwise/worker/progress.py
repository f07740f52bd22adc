"""The worker's progress reports: written to the session row, throttled, with a heartbeat.

`JobProgress` is the run's `RunCallback` for a job: it turns the round's phases into the
bar's fraction and the message the page shows.

`ProgressReporter.report(phase, fraction, message)` is cheap to call often (PPO calls it once
per rollout): it writes at most every `min_interval_s`. A heartbeat thread rewrites the
latest report every `heartbeat_s` with the seconds the phase has been running, so a long
step without reports of its own (loading, the reward fit) still shows life about once a
second.
"""

import logging
import threading
import time
from collections.abc import Callable

from groupwise.run.progress import RunCallback
from groupwise.storage import Database
from groupwise.storage.progress import set_progress

log = logging.getLogger(__name__)


class ProgressReporter:
    """Reports one job's progress for `session_id` while it is in `expected_phase`.

    Use as a context manager (starts and stops the heartbeat). `on_tick` runs on the
    heartbeat thread every tick (the worker checks there that its parent is alive).
    """

    def __init__(
        self,
        db: Database,
        session_id: str,
        expected_phase: str,
        *,
        min_interval_s: float = 0.5,
        heartbeat_s: float = 1.0,
        on_tick: Callable[[], None] | None = None,
    ) -> None:
        self.db = db
        self.session_id = session_id
        self.expected_phase = expected_phase
        self.min_interval_s = min_interval_s
        self.heartbeat_s = heartbeat_s
        self.on_tick = on_tick
        self._lock = threading.Lock()
        self._latest = ("", 0.0, "")
        self._phase_started = time.monotonic()
        self._written = 0.0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def __enter__(self) -> "ProgressReporter":
        self._thread = threading.Thread(target=self._beat, name="progress", daemon=True)
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()

    def report(self, phase: str, fraction: float, message: str, *, force: bool = False) -> None:
        """Note progress; write it now when forced, on a new phase, or when due."""
        with self._lock:
            new_phase = phase != self._latest[0]
            if new_phase:
                self._phase_started = time.monotonic()
            self._latest = (phase, fraction, message)
            due = time.monotonic() - self._written >= self.min_interval_s
        if force or new_phase or due:
            self._write(phase, fraction, message)

    def _write(self, phase: str, fraction: float, message: str) -> None:
        with self._lock:
            self._written = time.monotonic()
        try:
            with self.db.write() as s:
                set_progress(s, self.session_id, self.expected_phase, phase, fraction, message)
        except Exception:  # progress is best effort: never let it fail the job
            log.exception("could not write progress of %s", self.session_id)

    def _beat(self) -> None:
        while not self._stop.wait(self.heartbeat_s):
            if self.on_tick is not None:
                self.on_tick()
            with self._lock:
                phase, fraction, message = self._latest
                quiet = time.monotonic() - self._written >= self.heartbeat_s
                running = time.monotonic() - self._phase_started
            if phase and quiet:
                self._write(phase, fraction, f"{message} ({running:.0f} s)")


_PHASES: dict[str, tuple[float, float]] = {
    # phase: (fraction at its start, share of the bar it fills), by the seconds each took
    # preparing a Hopper round of 100 behaviours of 188 steps on 2 busy cores (issue 23):
    # sampling 7-21 s, DTW 2-3 s, clips 35-46 s (the render workers' start included)
    "load": (0.01, 0.0),
    "sample": (0.02, 0.23),
    "dtw": (0.25, 0.05),
    "clips": (0.3, 0.67),
    "suggestions": (0.97, 0.0),
    "reward": (0.03, 0.0),
    "ppo": (0.1, 0.78),
    "eval": (0.9, 0.0),
    "checkpoint": (0.95, 0.0),
    "video": (0.96, 0.0),
    "package": (0.98, 0.0),
}

_FREQUENT = frozenset({"sample", "dtw", "clips", "ppo"})
"""Phases that report often: written when due (`ProgressReporter.min_interval_s`)."""


def _message(phase: str, done: int, total: int) -> str:
    return {
        "load": "loading the policy and reward model",
        "sample": f"sampling behaviours from the policy: {done:,} / {total:,} steps",
        "dtw": f"measuring how behaviours differ (DTW): {done:,} / {total:,} pairs",
        "clips": f"rendering posters {done} / {total} (each clip when first asked for)",
        "suggestions": "computing suggestions",
        "reward": f"fitting the reward model on {total:,} pairs",
        # PPO collects whole rollouts (n_envs × n_steps): the total is what runs
        "ppo": f"PPO {done:,} / {total:,} steps (the steps asked, rounded up to whole rollouts)",
        "eval": "measuring the policy's true return",
        "checkpoint": "saving the checkpoint",
        "video": "filming the final agent",
        "package": "packing the agent for download",
    }[phase]


class JobProgress(RunCallback):
    """A run's phases as a job's progress bar (`ProgressReporter`)."""

    def __init__(self, reporter: ProgressReporter) -> None:
        self.reporter = reporter

    def on_phase(self, phase: str, done: int, total: int) -> None:
        start, share = _PHASES[phase]
        fraction = start + share * done / max(total, 1)
        message = _message(phase, done, total)
        self.reporter.report(phase, fraction, message, force=phase not in _FREQUENT)
