"""Training that never waits for the teacher, measured on a virtual clock (issue 24).

A *timed* teacher takes `TeacherConfig.pace_s` seconds of a virtual clock per comparison.
In a **continuous** round PPO does not wait for it: while the teacher answers one query,
PPO advances `TrainingConfig.ppo_steps_per_s` steps per virtual second (in whole rollouts;
a remainder under one rollout carries over to the next answer and is dropped at the
round's end; episodes run on across answers, fresh ones only at the round's start), and the
reward ensemble refits between rollouts as soon as
`refit_pairs` new pairs have arrived or `refit_s` seconds have passed since the last fit,
whichever comes first. A rollout's rewards therefore all come from one fit: the policy's
reward (`ensemble.mean_reward`, refitted in place) changes only between `learn` calls,
which are whole rollouts. A round is the teacher's unit of *fresh behaviours*: its pool is
sampled from the policy as it is when the round begins (`begin_round`).

In a **rounds** round the teacher answers the whole offer first and PPO trains afterwards
(`round.end_round`); with a timed teacher its record's `clock_s` adds the answers' time and
then the PPO steps at the same rate: the person waits while PPO runs.

Nothing here reads a real clock, so a run is the same on any machine for a seed
(`tests/integration/test_continuous.py`). The refits take no virtual time: they run on
another core than PPO, as the app's worker will run them.
"""

import time
from collections.abc import Sequence

from groupwise.oracles.base import Feedback
from groupwise.preferences.judgement import Judgement
from groupwise.reward import FitReport, fit
from groupwise.run.progress import RunCallback, as_callback
from groupwise.run.records import PhaseTimer, RoundRecord
from groupwise.run.round import (
    Offer,
    begin_round,
    clock_before,
    derive_pairs,
    finish_round,
)
from groupwise.run.run import Run
from groupwise.run.streams import RoundStreams, round_streams


def continuous_round(
    run: Run, feedback: Feedback, budget: int, callback: RunCallback | None = None
) -> RoundRecord:
    """One round of continuous training with a timed simulated teacher (module docstring).

    Raises:
        ValueError: the teacher has no pace, `pair_cap` is set (a cap needs the whole
            round's pairs), or the agent is not groupwise's own PPO.
    """
    cfg, callback = run.cfg, as_callback(callback)
    pace = cfg.teacher.pace_s
    if pace is None:
        raise ValueError("continuous training needs a timed teacher (TeacherConfig.pace_s)")
    if cfg.loop.pair_cap is not None:
        raise ValueError("continuous training adds pairs as they come: pair_cap must be None")
    rollout = run.ppo.rollout_steps
    index = run.next_round
    streams = round_streams(cfg.loop.seed, index)
    offer = begin_round(run, feedback.queries, budget, streams=streams)
    timer = PhaseTimer({"sample_s": offer.sample_s, "feedback_s": 0.0, "reward_s": 0.0})
    timer.seconds["ppo_s"] = 0.0
    clock = clock_before(run)
    trainer = _Trainer(run, streams, timer, callback)
    judgements: list[Judgement] = []
    fitted, last_fit = 0, clock  # judgements already in the dataset; when they were fitted
    credit = 0.0
    for query in offer.queries:
        credit += pace * cfg.training.ppo_steps_per_s
        rollouts = int(credit // rollout)
        if rollouts:
            trainer.learn(rollouts * rollout)
            credit -= rollouts * rollout
        clock += pace
        tick = time.perf_counter()
        judgements += feedback.teacher.answer(offer.pool, [query], streams.feedback)
        timer.seconds["feedback_s"] += time.perf_counter() - tick
        new = judgements[fitted:]
        if new and (
            _pair_count(run, new, index, fitted) >= cfg.training.refit_pairs
            or clock - last_fit >= cfg.training.refit_s
        ):
            trainer.refit(offer, judgements, fitted)
            fitted, last_fit = len(judgements), clock
    if judgements[fitted:]:
        trainer.refit(offer, judgements, fitted)
    return finish_round(
        run,
        offer,
        judgements,
        trainer.report,
        timer,
        callback,
        asked=len(offer.queries),
        clock_s=clock,
    )


class _Trainer:
    """PPO and the reward fit of one continuous round, each timed, each from its stream."""

    def __init__(
        self, run: Run, streams: RoundStreams, timer: PhaseTimer, callback: RunCallback
    ) -> None:
        self.run, self.streams, self.timer, self.callback = run, streams, timer, callback
        self.report: FitReport | None = None
        self.started = False

    def learn(self, steps: int) -> None:
        """`steps` more PPO steps: the round's first call seeds PPO from the round's stream
        and starts fresh episodes, later ones continue the episodes in flight."""
        tick = time.perf_counter()
        seed = None if self.started else int(self.streams.ppo.integers(2**31 - 1))
        self.started = True
        self.run.agent.learn(
            steps,
            seed,
            report=lambda done, total: self.callback.on_phase("ppo", done, total),
        )
        self.timer.seconds["ppo_s"] += time.perf_counter() - tick

    def refit(self, offer: Offer, judgements: Sequence[Judgement], fitted: int) -> None:
        """Add the pairs of `judgements[fitted:]` (keyed by their places in the round) and
        refit the ensemble on every pair so far."""
        run, loop = self.run, self.run.cfg.loop
        tick = time.perf_counter()
        new = judgements[fitted:]
        keys = range(fitted, len(judgements))
        pairs = derive_pairs(new, loop, offer.round, keys)
        first = len(run.dataset) == 0
        run.dataset.add(offer.pool.fragments, pairs, offer.round)
        self.callback.on_phase("reward", 0, len(run.dataset))
        multiplier = run.cfg.reward.initial_epoch_multiplier if first else 1.0
        epochs = max(1, round(run.cfg.reward.epochs * multiplier))
        if len(run.dataset):
            self.report = fit(run.ensemble, run.dataset, run.cfg.reward, self.streams.fit, epochs)
        self.timer.seconds["reward_s"] += time.perf_counter() - tick


def _pair_count(run: Run, new: Sequence[Judgement], round_index: int, first_key: int) -> int:
    """How many pairs `new` (keyed from `first_key`) will add: what the refit rule counts."""
    keys = range(first_key, first_key + len(new))
    return len(derive_pairs(new, run.cfg.loop, round_index, keys))


PAPER_CASES: dict[str, tuple[int, float]] = {
    "hopper-backflip": (1032, 34.0),
    "halfcheetah-standup": (601, 35.0),
    "walker-splits": (616, 40.0),
}
"""The paper's case studies: preference pairs a person gave, in minutes ("Example Cases")."""
GROUP_PAIRS_PER_COMPARISON = 2.71
"""Preference pairs per comparison of our Groupwise-DM on the three targets (400 comparisons
a run, 3 seeds each: 9,752 pairs of 3,600 comparisons, docs/results/case-studies); a
pairwise comparison gives one."""


def paper_pace(target: str | None, pairwise: bool) -> float:
    """A person's seconds per comparison at the paper's rate: the case study's seconds per
    preference pair (all three cases pooled when `target` is None: 2,249 pairs in 109 min)
    times the decision-maker's pairs per comparison. That a pairwise comparison takes a
    person as long as one pair of a group comparison is an assumption: the paper measured
    its case studies' rates with the groupwise interface only."""
    pairs, minutes = PAPER_CASES.get(target or "", _POOLED)
    per_pair = minutes * 60.0 / pairs
    return per_pair * (1.0 if pairwise else GROUP_PAIRS_PER_COMPARISON)


_POOLED = (
    sum(pairs for pairs, _ in PAPER_CASES.values()),
    sum(minutes for _, minutes in PAPER_CASES.values()),
)
