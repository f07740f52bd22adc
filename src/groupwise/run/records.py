"""A round's record: one row of ``rounds.csv`` (and of the app's round stats)."""

import csv
import dataclasses
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any


@dataclass(frozen=True)
class RoundRecord:
    """One row of `rounds.csv`."""

    round: int
    comparisons: int
    """The round's comparison budget (0 for a round without feedback)."""
    judgements: int
    """Judgements the round's teacher gave."""
    pairs: int
    """Preference pairs the round added to the dataset."""
    pairs_total: int
    label_error_rate: float
    """Share of the round's pairs whose label disagrees with the true returns."""
    label_error_rate_total: float
    reward_loss: float
    reward_accuracy: float
    reward_val_accuracy: float
    env_steps: int
    """The agent's PPO env steps so far."""
    true_return_mean: float
    """The greedy policy's true return after the round (nan without evaluation)."""
    true_return_std: float
    sample_s: float
    feedback_s: float
    reward_s: float
    ppo_s: float
    eval_s: float
    # how the round's feedback went (SPEC §7 diagnostics); nan where unknown (a person)
    queries_asked: float = math.nan
    """Queries the strategy proposed and the teacher was asked."""
    queries_unused: float = math.nan
    """The round's queries the strategy had nothing to propose for."""
    queries_skipped: float = math.nan
    """Asked queries that yielded no judgement (interference, a skipping teacher)."""
    candidates: float = math.nan
    """Group candidates the tree offered (nan for pairwise strategies)."""
    return_sd_over_noise: float = math.nan
    """sd of the pool's true returns ÷ the per-behaviour noise sd L·σ: below about 1 the
    labels are near coin flips whatever the strategy (the information limit)."""
    label_error_untied: float = math.nan
    """Share of the round's pairs of unequal true returns whose label disagrees with them (a
    label on two equal returns is arbitrary, not wrong): the teacher's error rate."""
    clock_s: float = math.nan
    """A timed teacher's virtual clock at the round's end, in seconds of the teacher's time
    (`groupwise.run.continuous`); nan for an untimed teacher."""
    target_score_mean: float = math.nan
    """In a target env (docs/case-studies.md): the greedy policy's episode score after the
    round, in the target's unit (e.g. backward turns; `Target.unit`), mean over the
    evaluation episodes; `true_return_mean` is the sum of its per-step scores. nan for other
    envs and without evaluation."""
    target_score_std: float = math.nan

    def stats(self) -> dict[str, object]:
        """The record as JSON-ready values (nan and inf as None): the app's round stats."""
        return {
            k: (None if isinstance(v, float) and not math.isfinite(v) else v)
            for k, v in dataclasses.asdict(self).items()
        }


REMOVED_COLUMNS = frozenset({"continued_from", "adopted_variant"})
"""Columns of runs written before issue 38 removed their mechanisms (training on from the
preferred policy, adopting a variant's push; docs/case-studies.md, "Measured and removed")."""


def read_record(row: Mapping[str, Any]) -> RoundRecord:
    """A record read back from a checkpoint's state, dropping `REMOVED_COLUMNS` (old runs).

    Raises:
        TypeError: another unknown or a missing column.
    """
    return RoundRecord(**{k: v for k, v in row.items() if k not in REMOVED_COLUMNS})


def write_records(path: Path, records: list[RoundRecord]) -> None:
    """Rewrite the per-round CSV atomically."""
    tmp = path.with_suffix(".tmp")
    with tmp.open("w", newline="") as handle:
        writer = csv.DictWriter(
            handle, fieldnames=[f.name for f in dataclasses.fields(RoundRecord)]
        )
        writer.writeheader()
        writer.writerows(dataclasses.asdict(r) for r in records)
    tmp.replace(path)


class PhaseTimer:
    """Wall time per named phase: `with timer("ppo"): ...`, then `timer.seconds`."""

    def __init__(self, seconds: dict[str, float] | None = None) -> None:
        self.seconds: dict[str, float] = dict(seconds or {})

    def __call__(self, phase: str) -> "PhaseTimer":
        self._phase = phase
        return self

    def __enter__(self) -> None:
        self._start = time.perf_counter()

    def __exit__(self, *exc: object) -> None:
        self.seconds[f"{self._phase}_s"] = time.perf_counter() - self._start
