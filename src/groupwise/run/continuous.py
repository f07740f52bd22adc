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
cut from PPO's own latest rollouts (issue 39: `ContinuousRound` records PPO's episodes,
`rl.recording`, the latest ones across rounds, and `begin_round` reads them through
`pool.recent.fresh_sources`, sampling what they lack from the policy), so the teacher judges
what the agent does now. It is cut while the teacher answers the round before's last query,
and PPO waits for that answer (`cut_next`): the pool is the policy's when its round opens,
and the app opens it without a wait (`worker.continuous_round`). Round 0, or a round after a
restart, is cut when it begins.

In a **rounds** round the teacher answers the whole offer first and PPO trains afterwards
(`round.end_round`); with a timed teacher its record's `clock_s` adds the answers' time and
then the PPO steps at the same rate: the person waits while PPO runs.

Nothing here reads a real clock, so a run is the same on any machine for a seed
(`tests/integration/test_continuous.py`). The refits take no virtual time: they run on
another core than PPO, as the app's worker will run them.
"""

import dataclasses
import time
from collections.abc import Callable, Sequence
from typing import NamedTuple

from groupwise.behaviour.pool import BehaviourPool
from groupwise.clips.timing import clip_timing, step_seconds
from groupwise.pool.recent import fresh_sources, kept_tag
from groupwise.pool.sampling import windows_to_sample
from groupwise.preferences.judgement import Judgement
from groupwise.query.strategies import QueryStrategy
from groupwise.reward import FitReport, fit
from groupwise.rl.recording import RolloutRecorder, record_rollouts, recorder_of_agent
from groupwise.run.pairs import derive_pairs
from groupwise.run.progress import RunCallback, as_callback
from groupwise.run.records import PhaseTimer, RoundRecord
from groupwise.run.round import (
    Offer,
    begin_round,
    clock_before,
    finish_round,
    pool_size,
)
from groupwise.run.run import Run
from groupwise.run.streams import RoundStreams, round_streams
from groupwise.teachers.base import Feedback


class NextRound(NamedTuple):
    """The next round's offer, cut while the teacher answered this round's last query
    (`continuous_round`), and the round streams it was cut with (its teacher goes on with
    their `feedback` stream)."""

    offer: Offer
    streams: RoundStreams


def cut_next(
    run: Run,
    strategy: QueryStrategy,
    budget: int,
    round_index: int,
    n_queries: int | None = None,
    callback: RunCallback | None = None,
    judged: BehaviourPool | None = None,
) -> NextRound:
    """Round `round_index`'s offer of `budget` comparisons (`n_queries` proposed, default
    `budget`), cut now from the run's latest rollouts (`pool.recent.fresh_sources`) and a
    share from the kept policy, which PPO goes back to first when the answers on the `judged`
    pool (the open round's) prefer it (`run.kept_policy`), while
    round `round_index` − 1 is open (the app's `worker.jobs.cut_fresh` cuts it alike: as
    many comparisons before the round's end as its cut takes at the person's pace,
    `worker.continuous_round.comparisons_ahead`; a cut here takes no virtual time, so at
    the last answer)."""
    loop = run.cfg.loop
    streams = round_streams(loop.seed, round_index)
    tag = kept_tag(loop)
    if run.kept.choose(run.ppo, run.ensemble, judged, tag, round_index) == "back":
        recorder = recorder_of_agent(run.agent)
        if recorder is not None:  # what PPO played since is not the policy's any more
            recorder.clear()
    kept = run.kept.share(run.ppo, loop, run.cfg.training.kept_share)
    offer = begin_round(
        run,
        strategy,
        budget,
        n_queries=n_queries,
        streams=streams,
        round_index=round_index,
        sources=fresh_sources(loop, kept),
        callback=callback,
    )
    return NextRound(offer, streams)


def continuous_round(
    run: Run,
    feedback: Feedback,
    budget: int,
    callback: RunCallback | None = None,
    *,
    staged: NextRound | None = None,
    following: int | None = None,
) -> tuple[RoundRecord, NextRound | None]:
    """One round of continuous training with a timed simulated teacher (module docstring):
    its record, and with `following` (the next round's budget) the next round cut during
    the last answer, which PPO waits out (`cut_next`; pass it back as `staged`).

    Raises:
        ValueError: the teacher has no pace, or `pair_cap` is set (a cap needs the whole
            round's pairs).
        TypeError: the agent is not groupwise's own PPO (slices need its rollout size).
    """
    cfg, callback = run.cfg, as_callback(callback)
    pace = cfg.teacher.pace_s
    if pace is None:
        raise ValueError("continuous training needs a timed teacher (TeacherConfig.pace_s)")
    rollout = run.ppo.rollout_steps
    if staged is None or staged.offer.round != run.next_round:  # round 0, or a restart
        staged = cut_next(run, feedback.queries, budget, run.next_round)
    offer, streams = staged
    clock = clock_before(run)
    continuous = ContinuousRound(run, offer, streams, clock, callback)
    timer = continuous.timer
    judgements: list[Judgement] = []
    credit = 0.0
    following_round = None
    for i, query in enumerate(offer.queries):
        if following and i == len(offer.queries) - 1:
            # the round's end is in sight: its next pool is cut now, and PPO waits for the
            # last answer, so that the pool is the policy's when the round opens
            following_round = cut_next(
                run, feedback.queries, following, offer.round + 1, judged=offer.pool
            )
        else:
            credit += pace * cfg.training.ppo_steps_per_s
            rollouts = int(credit // rollout)
            if rollouts:
                continuous.learn(rollouts * rollout)
                credit -= rollouts * rollout
        clock += pace
        tick = time.perf_counter()
        judgements += feedback.teacher.answer(offer.pool, [query], streams.feedback)
        timer.seconds["feedback_s"] += time.perf_counter() - tick
        continuous.update(list(enumerate(judgements)), clock)
    continuous.update(list(enumerate(judgements)), clock, final=True)
    record = finish_round(
        run,
        offer,
        judgements,
        continuous.report,
        timer,
        callback,
        asked=len(offer.queries),
        clock_s=clock,
    )
    return record, following_round


class ContinuousRound:
    """One round trained while its judgements arrive: PPO in slices (`learn`), the reward
    ensemble refitted between them (`update`) once `TrainingConfig.refit_pairs` pairs have
    changed (new ones, or an undone judgement's) or `refit_s` seconds have passed since the
    last fit with anything changed, and at once for a run's very first pairs. Each refit
    fits on the rounds before plus the pairs of the judgements given now (each keyed by its
    place in the round, as `end_round` derives them), so the dataset at the round's end is
    the one `end_round` would build. The headless continuous round and the app's worker
    (which reads the judgements from the database) drive it alike; `clock` is whatever
    clock the caller keeps."""

    def __init__(
        self,
        run: Run,
        offer: Offer,
        streams: RoundStreams,
        clock: float,
        callback: RunCallback | None = None,
    ) -> None:
        if run.cfg.loop.pair_cap is not None:
            raise ValueError("continuous training adds pairs as they come: pair_cap must be None")
        self.run, self.offer, self.streams = run, offer, streams
        self.callback = as_callback(callback)
        self.timer = PhaseTimer({"sample_s": offer.sample_s, "feedback_s": 0.0})
        self.timer.seconds.update(reward_s=0.0, ppo_s=0.0)
        self.base = dataclasses.replace(run.dataset)  # the rounds before; `add` copies
        self.fitted: dict[int, int] = {}  # key → pairs, of the judgements in the last fit
        self.last_fit = clock
        self.report: FitReport | None = None
        self.started = False
        self.recorder = recorder_for(run, offer.budget)
        run.kept.begin(run.ppo, offer.round)

    def learn(self, steps: int, stop: Callable[[], bool] | None = None) -> bool:
        """`steps` more PPO steps: the round's first call seeds PPO from the round's stream
        and starts fresh episodes, later ones continue the episodes in flight. `stop` ends
        the rollout in progress untrained once it says True (`PPOAgent.learn`: the app's
        worker when the round ends meanwhile, so that the next round opens without waiting
        for the rest of it); False when it did."""
        tick = time.perf_counter()
        seed = None if self.started else int(self.streams.ppo.integers(2**31 - 1))
        self.started = True
        before = self.run.agent.num_timesteps
        self.run.ppo.learn(
            steps,
            seed,
            report=lambda done, total: self.callback.on_phase("ppo", done, total),
            stop=stop,
        )
        self.timer.seconds["ppo_s"] += time.perf_counter() - tick
        return self.run.agent.num_timesteps - before >= steps

    def update(
        self, keyed: Sequence[tuple[int, Judgement]], clock: float, *, final: bool = False
    ) -> bool:
        """Refit on `keyed` (the round's judgements now, with their keys) when it is due,
        or whenever anything changed with `final`; True when it refitted."""
        loop, training = self.run.cfg.loop, self.run.cfg.training
        round_index = self.offer.round
        now = {key: judgement for key, judgement in keyed}
        added = [key for key in now if key not in self.fitted]
        removed = [key for key in self.fitted if key not in now]
        if not added and not removed:
            return False
        new = [now[key] for key in added]
        changed = len(derive_pairs(new, loop, round_index, added)) + sum(
            self.fitted[key] for key in removed
        )
        due = changed >= training.refit_pairs or clock - self.last_fit >= training.refit_s
        first = len(self.run.dataset) == 0  # nothing fitted yet: PPO waits for this fit
        if not (due or final or first):
            return False
        self._refit(keyed)
        self.last_fit = clock
        return True

    def _refit(self, keyed: Sequence[tuple[int, Judgement]]) -> None:
        run, loop, round_index = self.run, self.run.cfg.loop, self.offer.round
        tick = time.perf_counter()
        derived = {key: derive_pairs([j], loop, round_index, [key]) for key, j in keyed}
        self.fitted = {key: len(pairs) for key, pairs in derived.items()}
        dataset = dataclasses.replace(self.base)
        pairs = [pair for key, _ in keyed for pair in derived[key]]
        dataset.add(self.offer.pool.fragments, pairs, round_index)
        run.dataset = dataset
        self.callback.on_phase("reward", 0, len(dataset))
        # the run's first fit gets `initial_epoch_multiplier` × the epochs, as round 0's does
        first = len(self.base) == 0 and self.report is None
        multiplier = run.cfg.reward.initial_epoch_multiplier if first else 1.0
        epochs = max(1, round(run.cfg.reward.epochs * multiplier))
        if len(dataset):
            self.report = fit(run.ensemble, dataset, run.cfg.reward, self.streams.fit, epochs)
        self.timer.seconds["reward_s"] += time.perf_counter() - tick


def recorder_for(run: Run, budget: int) -> RolloutRecorder:
    """The recorder of the run's PPO envs (`rl.recording`), set up the first time: it keeps
    the windows a pool of a round of `budget` comparisons is chosen from, with the physics
    states its clips and posters are rendered from."""
    loop = run.cfg.loop
    probe = run.make_env()
    try:
        offsets = clip_timing(step_seconds(probe), steps=loop.fragment_length).snapshot_offsets
    finally:
        probe.close()
    windows = windows_to_sample(
        pool_size(loop, budget), loop.pool_oversample, loop.pool_windows_max
    )
    agent = run.ppo
    return record_rollouts(
        agent.venv,
        loop.fragment_length,
        offsets,
        windows,
        lambda: agent.num_timesteps,
        agent.rollout_steps,
    )


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
