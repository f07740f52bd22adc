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

Its parts: `target_evaluation` (a policy's episodes scored by the target), `pool_scores`
(how much of the behaviour each round's pool holds), `case_record` (a row of
``case-study.csv``).
"""

import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from groupwise.config import RunConfig
from groupwise.envs import Target
from groupwise.run.headless import feedback_of, hand_over, round_plan, run_rounds
from groupwise.run.progress import CallbackList, OnRoundEnd, ProgressBars
from groupwise.run.records import RoundRecord
from groupwise.run.run import Run
from groupwise.run.streams import eval_rng
from groupwise.run.takeaway import TakeawayChoice, TakeawayConfig
from groupwise.study.case_studies.case_record import CaseRecord, write_records
from groupwise.study.case_studies.film import Film, film_episode, write_film
from groupwise.study.case_studies.pool_scores import PoolRecorder
from groupwise.study.case_studies.reward_rank import POSTURES, rank_rng, reward_rank
from groupwise.study.case_studies.target_evaluation import TargetEvaluation, evaluate_target
from groupwise.teachers import Feedback

CASE_FILE = "case-study.csv"
VIDEO_FILE = "final.mp4"
STRIP_FILE = "strip.png"
SUMMARY_FILE = "summary.json"


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
            write_records(out / CASE_FILE, rows)

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
