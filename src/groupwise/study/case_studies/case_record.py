"""A case study's per-round record: a row of ``case-study.csv`` (the preferences so far, the
target score, the success and stretch rates, the label error, the pool's scores, the learned
reward's ranking and the wall time of each phase), and writing the rows."""

import csv
import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from groupwise.envs import Target
from groupwise.preferences.dataset import PreferenceDataset
from groupwise.run.records import RoundRecord
from groupwise.study.case_studies.reward_rank import RewardRank
from groupwise.study.case_studies.target_evaluation import TargetEvaluation
from groupwise.types import FloatArray


@dataclass(frozen=True)
class CaseRecord:
    """One row of ``case-study.csv``: a round and the target score after it."""

    round: int
    comparisons_total: int
    """The rounds' comparison budgets so far (``rounds.csv``'s ``queries_asked`` says how
    many of them a strategy found queries for)."""
    judgements_total: int
    pairs_total: int
    """Binary preferences (pairs) so far: what the paper counts (601, 616, 1,032)."""
    label_error_rate: float
    label_error_rate_total: float
    tied_share_total: float
    """Share of the pairs so far whose two behaviours have exactly equal target scores (a
    target scores 0 until the behaviour appears, so early pools are full of ties)."""
    label_error_untied_total: float
    """Label error over the pairs so far whose target scores differ: how often the labels
    rank two different behaviours wrongly (a label on a tie is arbitrary, not wrong)."""
    pool_score_sd: float
    """The sd over the round's pool of its behaviours' mean per-step target scores
    (`pool_scores`): how much there was to tell apart ..."""
    pool_score_max: float
    """... and the best behaviour's: whether the pool held the behaviour at all."""
    env_steps: int
    target_score_mean: float
    target_score_std: float
    success_rate: float
    """Share of evaluation episodes at or above the target's threshold."""
    stretch_rate: float
    true_return_mean: float
    """Mean sum of per-step target scores (what the decision-maker perceives, noise-free)."""
    sample_s: float
    feedback_s: float
    reward_s: float
    ppo_s: float
    eval_s: float
    """The target evaluation (the loop's own evaluation is off: ``eval_episodes`` = 0)."""
    wall_s: float
    """Wall time since the study started, evaluations included."""
    reward_rank_rho: float = math.nan
    """Spearman ρ between the learned reward and the target's step score over the steps of
    fresh greedy and stochastic episodes of the policy (issue 41,
    `study.case_studies.reward_rank`) ..."""
    reward_split: float = math.nan
    """... and, for walker-splits, the learned reward's mean per step on held-split steps ..."""
    reward_nonsplit: float = math.nan
    """... on every other step ..."""
    reward_stance: float = math.nan
    """... and on the wide, tilted stance among them (thighs ≥ 90° apart, both feet down,
    torso past 60°)."""

    @classmethod
    def of(
        cls,
        record: RoundRecord,
        previous: "CaseRecord | None",
        dataset: PreferenceDataset,
        evaluation: TargetEvaluation,
        target: Target,
        eval_s: float,
        wall_s: float,
        behaviour_scores: FloatArray | None = None,
        rank: RewardRank | None = None,
    ) -> "CaseRecord":
        """The row of `record`; `behaviour_scores`: its pool's (`pool_scores`; None: none);
        `rank`: the learned reward's ranking of the policy's steps (None: not measured)."""
        scores = np.full(1, np.nan)  # no pool scored, or an empty one
        if behaviour_scores is not None and len(behaviour_scores):
            scores = behaviour_scores
        return cls(
            round=record.round,
            comparisons_total=record.comparisons + (previous.comparisons_total if previous else 0),
            judgements_total=record.judgements + (previous.judgements_total if previous else 0),
            pairs_total=record.pairs_total,
            label_error_rate=record.label_error_rate,
            label_error_rate_total=record.label_error_rate_total,
            tied_share_total=float(dataset.tied().mean()) if len(dataset) else math.nan,
            label_error_untied_total=dataset.label_error_rate(untied=True),
            pool_score_sd=float(scores.std()),
            pool_score_max=float(scores.max()),
            env_steps=record.env_steps,
            **evaluation.summary(target),
            sample_s=record.sample_s,
            feedback_s=record.feedback_s,
            reward_s=record.reward_s,
            ppo_s=record.ppo_s,
            eval_s=eval_s,
            wall_s=wall_s,
            **_rank_columns(rank),
        )


def _rank_columns(rank: RewardRank | None) -> dict[str, float]:
    if rank is None:
        return {}
    posture = rank.by_posture
    return {
        "reward_rank_rho": rank.rho,
        **{
            f"reward_{name}": posture[name]
            for name in ("split", "nonsplit", "stance")
            if name in posture
        },
    }


def write_records(path: Path, rows: list[CaseRecord]) -> None:
    """Write `rows` to `path` as CSV, one column per field, replacing the file at once."""
    tmp = path.with_suffix(".tmp")
    with tmp.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=[f.name for f in dataclasses.fields(CaseRecord)])
        writer.writeheader()
        writer.writerows(dataclasses.asdict(r) for r in rows)
    tmp.replace(path)
