"""How much a run's learned reward moves between refits (issue 20, "kept once learned").

For a run directory with one checkpoint per round (``groupwise train``, ``groupwise
case-study``), `drift` compares each round's reward fit with the one before it on the same
states, the fragments the earlier fit was trained on:

- ``fit_corr``: the Pearson correlation of the two fits' predicted returns (the ensemble
  mean) on those fragments; 1 means the refit kept the reward's ranking there;
- ``truth_before`` / ``truth_after``: each fit's correlation with the true returns of the
  same fragments;
- ``score_before`` / ``score_after``: the greedy policy's target score (or true return)
  after the two rounds, from ``case-study.csv`` or ``rounds.csv``.

    python -m groupwise.study.reward_drift RUN_DIR ...    # a table per run
"""

import argparse
import csv
import itertools
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from groupwise.preferences.dataset import PreferenceDataset
from groupwise.reward import RewardEnsemble
from groupwise.run.checkpoint import DATASET_FILE, REWARD_FILE, checkpoint_dir
from groupwise.types import FloatArray


@dataclass(frozen=True)
class Refit:
    """Round `round`'s fit against round `round` − 1's (module docstring)."""

    round: int
    fragments: int
    fit_corr: float
    truth_before: float
    truth_after: float
    score_before: float
    score_after: float


def fragment_rounds(dataset: PreferenceDataset) -> np.ndarray:
    """(F,) the first round whose pairs use each fragment."""
    first = np.full(dataset.n_fragments, np.iinfo(np.int64).max)
    for column in (0, 1):
        np.minimum.at(first, dataset.pairs[:, column], dataset.rounds)
    return first


def _corr(a: FloatArray, b: FloatArray) -> float:
    if len(a) < 3 or a.std() == 0 or b.std() == 0:
        return math.nan
    return float(np.corrcoef(a, b)[0, 1])


def _scores(run: Path) -> dict[int, float]:
    """Each round's greedy score: the target score of ``case-study.csv``, else the true
    return (or target score) of ``rounds.csv``."""
    for name, key in (("case-study.csv", "target_score_mean"), ("rounds.csv", "true_return_mean")):
        path = run / name
        if path.is_file():
            with path.open() as handle:
                rows = list(csv.DictReader(handle))
            if (
                name == "rounds.csv"
                and rows
                and rows[0].get("target_score_mean") not in ("", "nan")
            ):
                key = "target_score_mean"
            return {int(r["round"]): float(r[key] or "nan") for r in rows}
    return {}


def drift(run: Path) -> list[Refit]:
    """Each refit of the run against the fit before it (module docstring).

    Raises:
        FileNotFoundError: a round's checkpoint is missing.
    """
    rounds = sorted(int(p.name.split("-")[1]) for p in (run / "checkpoints").glob("round-[0-9]*"))
    last = checkpoint_dir(run, rounds[-1])
    dataset = PreferenceDataset.load(last / DATASET_FILE)
    first = fragment_rounds(dataset)
    scores = _scores(run)
    predicted = {}
    for r in rounds:
        ensemble = RewardEnsemble.load(checkpoint_dir(run, r) / REWARD_FILE)
        predicted[r] = ensemble.returns(dataset.obs, dataset.acts).mean(axis=1)
    refits = []
    for before, after in itertools.pairwise(rounds):
        seen = first <= before
        a, b, truth = predicted[before][seen], predicted[after][seen], dataset.true_returns[seen]
        refits.append(
            Refit(
                round=after,
                fragments=int(seen.sum()),
                fit_corr=_corr(a, b),
                truth_before=_corr(a, truth),
                truth_after=_corr(b, truth),
                score_before=scores.get(before, math.nan),
                score_after=scores.get(after, math.nan),
            )
        )
    return refits


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", nargs="+", type=Path)
    args = parser.parse_args(argv)
    print(
        "| run | refit | fragments | corr(fit r−1, fit r) | truth r−1 | truth r | score r−1 → r |"
    )
    print("|---|---:|---:|---:|---:|---:|---|")
    for run in args.runs:
        for refit in drift(run):
            print(
                f"| {run.name} | {refit.round} | {refit.fragments} | {refit.fit_corr:.2f} | "
                f"{refit.truth_before:.2f} | {refit.truth_after:.2f} | "
                f"{refit.score_before:.2f} → {refit.score_after:.2f} |"
            )


if __name__ == "__main__":
    main()
