"""A case study (paper §"Example Cases"): teach a behaviour that has no reward and measure it
by its target score.

The loop is `groupwise train`'s (`run.headless.run_rounds` over a `Run`; the same checkpoints,
``config.json`` and ``rounds.csv``); the target env pays PPO nothing, its per-step target
score is the true reward the simulated decision-maker perceives (with the SPEC §7 noise).
After every round the greedy policy is evaluated on the target: ``case-study.csv`` gets
the preferences so far, the target score (mean, sd), the success and stretch rates, the
label error and the wall time of each phase. At the end the evaluated episode with the
highest target score is filmed (``final.mp4``, ``strip.png``,
`groupwise.study.case_studies.film`) and ``summary.json`` states the target, its thresholds
and the final evaluation.
"""

import csv
import dataclasses
import json
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from groupwise.behaviour.pool import BehaviourPool
from groupwise.config import RunConfig
from groupwise.envs import TARGET_TOTAL_KEY, Target
from groupwise.envs.targets import TARGET_SCORE_KEY
from groupwise.preferences.dataset import PreferenceDataset
from groupwise.query.strategies import Query, QueryStrategy
from groupwise.rl.policy import Policy
from groupwise.rl.rollout import EnvFactory
from groupwise.run.headless import feedback_of, hand_over, round_plan, run_rounds
from groupwise.run.progress import CallbackList, OnRoundEnd, ProgressBars
from groupwise.run.records import RoundRecord
from groupwise.run.run import Run
from groupwise.run.streams import eval_rng
from groupwise.run.takeaway import TakeawayChoice, TakeawayConfig
from groupwise.study.case_studies.film import Film, film_episode, write_film
from groupwise.study.case_studies.reward_rank import (
    POSTURES,
    RewardRank,
    rank_rng,
    reward_rank,
)
from groupwise.teachers import Feedback
from groupwise.types import FloatArray

CASE_FILE = "case-study.csv"
VIDEO_FILE = "final.mp4"
STRIP_FILE = "strip.png"
SUMMARY_FILE = "summary.json"


@dataclass(frozen=True)
class TargetEvaluation:
    """Episodes of a policy scored by a target (their actions kept for filming)."""

    scores: FloatArray  # (E,) episode target scores
    returns: FloatArray  # (E,) sums of the per-step scores (the env's true return)
    reset_seeds: tuple[int, ...]  # (E,)
    actions: tuple[np.ndarray, ...]  # E × (T, *action_shape) raw env actions
    step_scores: tuple[FloatArray, ...]  # E × (T,)

    def success_rate(self, target: Target) -> float:
        return float(np.mean([target.succeeds(s) for s in self.scores]))

    def stretch_rate(self, target: Target) -> float:
        return float(np.mean([target.stretches(s) for s in self.scores]))

    def summary(self, target: Target) -> dict[str, float]:
        """The target score's mean and sd, the success and stretch rates and the mean sum
        of step scores, under the names of `CaseRecord`'s columns."""
        return {
            "target_score_mean": float(self.scores.mean()),
            "target_score_std": float(self.scores.std()),
            "success_rate": self.success_rate(target),
            "stretch_rate": self.stretch_rate(target),
            "true_return_mean": float(self.returns.mean()),
        }


def evaluate_target(
    make_env: EnvFactory, policy: Policy, n_episodes: int, rng: np.random.Generator
) -> TargetEvaluation:
    """`n_episodes` whole episodes of `policy` side by side in a target env from `make_env`,
    each reset with a seed drawn from `rng`; the score of each is the env's
    ``info["target_total"]`` at its last step.

    Raises:
        ValueError: `n_episodes` < 1.
    """
    if n_episodes < 1:
        raise ValueError(f"need at least one episode, got {n_episodes}")
    envs = [make_env() for _ in range(n_episodes)]
    seeds = [int(s) for s in rng.integers(0, 2**31 - 1, size=n_episodes)]
    try:
        obs = np.stack([env.reset(seed=s)[0] for env, s in zip(envs, seeds, strict=True)])
        actions: list[list[np.ndarray]] = [[] for _ in envs]
        scores: list[list[float]] = [[] for _ in envs]
        totals = np.zeros(n_episodes)
        running = list(range(n_episodes))
        while running:
            batch = np.asarray(policy.act(obs[running].astype(np.float32), rng))
            still = []
            for i, action in zip(running, batch, strict=True):
                obs[i], _, terminated, truncated, info = envs[i].step(action)
                actions[i].append(action)
                scores[i].append(float(info[TARGET_SCORE_KEY]))
                totals[i] = info[TARGET_TOTAL_KEY]
                if not (terminated or truncated):
                    still.append(i)
            running = still
    finally:
        for env in envs:
            env.close()
    steps = tuple(np.asarray(s) for s in scores)
    return TargetEvaluation(
        scores=totals,
        returns=np.array([s.sum() for s in steps]),
        reset_seeds=tuple(seeds),
        actions=tuple(np.asarray(a) for a in actions),
        step_scores=steps,
    )


def pool_scores(pool: BehaviourPool) -> np.ndarray:
    """Each behaviour's mean per-step target score (N,): its true return over its length."""
    lengths = np.array([f.length for f in pool.fragments], dtype=float)
    return np.asarray(pool.true_returns, dtype=float) / lengths


class PoolRecorder:
    """A query strategy that scores every pool it is asked about (`pool_scores`, kept per
    round: a continuous run asks about round r + 1's pool before round r ends) and lets the
    run's own strategy answer."""

    def __init__(self, inner: QueryStrategy) -> None:
        self.inner = inner
        self.scores: dict[int, FloatArray] = {}

    def propose(self, pool: BehaviourPool, n_queries: int, rng: np.random.Generator) -> list[Query]:
        self.scores[pool.round] = pool_scores(pool)
        return self.inner.propose(pool, n_queries, rng)

    def __getattr__(self, name: str) -> object:  # the strategy's `candidates`, if it has them
        return getattr(self.inner, name)


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


@dataclass(frozen=True)
class CaseStudy:
    """What a case study produced."""

    records: list[CaseRecord]
    evaluation: TargetEvaluation
    """The take-away round's evaluation."""
    filmed: int | None
    """Index in `evaluation` of the filmed episode (None: not filmed)."""
    choice: TakeawayChoice
    """Which round's policy the run handed over (``agent.zip``)."""


def run_case_study(
    cfg: RunConfig,
    target: Target,
    out: Path,
    *,
    eval_episodes: int = 5,
    film: bool = True,
    show_progress: bool = True,
    feedback: Feedback | None = None,
    takeaway: TakeawayConfig | None = None,
) -> CaseStudy:
    """Run `cfg` (its env must be `target.env`) into `out` (module docstring). The round
    handed over (``agent.zip``, `run.headless.hand_over`) is the one the teacher prefers
    by default (`takeaway`), and the film shows its best evaluated episode.

    Raises:
        ValueError: the config's env is not the target's, its decision-maker is unknown, or
            `eval_episodes` < 1.
        RenderingUnavailableError: filming without an offscreen GL backend.
    """
    if cfg.loop.env != target.env:
        raise ValueError(f"the config's env {cfg.loop.env!r} is not {target.name}'s {target.env}")
    if eval_episodes < 1:
        raise ValueError(f"need at least one evaluation episode, got {eval_episodes}")
    own = feedback or feedback_of(cfg)
    recorder = PoolRecorder(own.queries)
    feedback = Feedback(recorder, own.teacher)
    started = time.perf_counter()
    rows: list[CaseRecord] = []
    evaluations: list[TargetEvaluation] = []
    with Run.create(cfg, out) as run:
        postures = POSTURES[target.name](run.make_env) if target.name in POSTURES else None

        def scored(record: RoundRecord) -> None:
            begin = time.perf_counter()
            evaluation = evaluate_target(
                run.make_env,
                run.agent.policy(deterministic=True),
                eval_episodes,
                eval_rng(cfg.loop.seed),
            )
            rank = reward_rank(  # issue 41: the learned reward on the policy's own steps
                run.make_env,
                run.agent,
                run.ensemble.mean_reward,
                eval_episodes,
                rank_rng(cfg.loop.seed, record.round),
                postures,
            )
            now = time.perf_counter()
            previous = rows[-1] if rows else None
            rows.append(
                CaseRecord.of(
                    record,
                    previous,
                    run.dataset,
                    evaluation,
                    target,
                    now - begin,
                    now - started,
                    recorder.scores.get(record.round),
                    rank,
                )
            )
            evaluations.append(evaluation)
            _write_rows(out / CASE_FILE, rows)

        bars = ProgressBars(len(round_plan(cfg.loop)), desc=target.name) if show_progress else None
        callback = CallbackList([OnRoundEnd(scored), *([bars] if bars else [])])
        try:
            run_rounds(run, feedback, callback)
            choice = hand_over(run, feedback, takeaway or TakeawayConfig(), callback)
        finally:
            if bars is not None:
                bars.close()
    evaluation = evaluations[[r.round for r in rows].index(choice.round)]
    best = int(np.argmax(evaluation.scores))
    movie = None
    if film:
        movie = film_episode(
            target,
            evaluation.actions[best],
            evaluation.reset_seeds[best],
            evaluation.step_scores[best],
        )
        write_film(movie, out / VIDEO_FILE, out / STRIP_FILE)
    summary = _summary(
        cfg, target, rows, evaluations[-1], evaluation, best if film else None, movie
    )
    chosen = rows[[r.round for r in rows].index(choice.round)]
    summary["takeaway"] = {
        **choice.to_dict(),
        "score_mean": chosen.target_score_mean,
        "success_rate": chosen.success_rate,
        "stretch_rate": chosen.stretch_rate,
        "why": "the round whose greedy episodes the teacher preferred (takeaway.json)",
    }
    if "filmed" in summary:
        summary["filmed"]["round"] = choice.round
    (out / SUMMARY_FILE).write_text(json.dumps(summary, indent=2) + "\n")
    return CaseStudy(rows, evaluation, best if film else None, choice)


def _write_rows(path: Path, rows: list[CaseRecord]) -> None:
    tmp = path.with_suffix(".tmp")
    with tmp.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=[f.name for f in dataclasses.fields(CaseRecord)])
        writer.writeheader()
        writer.writerows(dataclasses.asdict(r) for r in rows)
    tmp.replace(path)


def _summary(
    cfg: RunConfig,
    target: Target,
    rows: list[CaseRecord],
    final: TargetEvaluation,
    evaluation: TargetEvaluation,
    filmed: int | None,
    movie: Film | None,
) -> dict[str, Any]:
    """`final`: the last round's evaluation; `evaluation`: the filmed (take-away) round's."""
    last = rows[-1]
    summary: dict[str, Any] = {
        "target": {
            "name": target.name,
            "env": target.env,
            "unit": target.unit,
            "threshold": target.threshold,
            "stretch": target.stretch,
            "description": target.description,
        },
        "decision_maker": cfg.loop.decision_maker,
        "comparisons": last.comparisons_total,
        "preference_pairs": last.pairs_total,
        "env_steps": last.env_steps,
        "wall_s": last.wall_s,
        "final": {
            "scores": final.scores.tolist(),
            "score_mean": last.target_score_mean,
            "success_rate": last.success_rate,
            "stretch_rate": last.stretch_rate,
        },
    }
    if filmed is not None and movie is not None:
        summary["filmed"] = {
            "episode": filmed,
            "reset_seed": evaluation.reset_seeds[filmed],
            "score": float(evaluation.scores[filmed]),
            "why": "the take-away round's evaluated episode with the highest target score",
            "video": VIDEO_FILE,
            "fps": movie.fps,
            "strip": STRIP_FILE,
            "strip_seconds": [round(float(t) * movie.step_seconds, 4) for t in movie.strip_steps],
        }
    return summary
