"""One continuous round in the worker: its state (`ContinuousTraining`) and one slice of its
training (`train_slice`), as `worker.continuous` schedules them.

A slice reads the round's judgements from the database (`round_judgements`: undone ones
left out, each keyed by its place in the round), refits the reward ensemble when due
(`run.continuous.ContinuousRound`: 20 changed pairs or 60 s), then trains one PPO rollout on the
latest fit — so the reward PPO sees changes only between rollouts. Every `CHECKPOINT_S`
seconds the policy and the ensemble go to ``checkpoints/live`` (`Run.save_mid_round`). A
rollout in progress when the round ends stops there, untrained (`round_ended`, read every
`STOP_POLL_S` seconds): the round's training job, which opens the next round while the
person waits, then waits for no more PPO (issue 39; it waited 1.3 s on Hopper).

A round that ends at its comparison budget, or by its timer, is seen coming: a few
comparisons before its budget (one, or as many as the person gives, at their pace, while a
cut as long as the last one runs: `comparisons_ahead`), or as many seconds before its timer
runs out as that cut takes, a slice cuts and publishes the next round's pool from the
latest rollouts (`stage_due`, `jobs.cut_fresh`) and PPO then waits for the round's end
(`holds`, at most `HOLD_S` seconds), so the pool is still the policy's when the round ends,
and the round's training job opens it at once (`jobs.train`'s `staged`) instead of sampling
while the person waits (issue 39: End round → next round ≤ 2 s). The next pool is chosen
and its suggestions made without the last few comparisons' pairs; a round the person ends
early ("End round") is cut when it ends.

The page sees the agent learn (`worker.curve`): each refit stores a point of the session's
learning curve (PPO steps, pairs, validation accuracy), and so does each evaluation of the
greedy policy's true return, the first before the round's first rollout, then whenever the
last one has finished and the slices have trained long enough (`curve.EVAL_MIN_S`,
`curve.EVAL_COST`); between them a point at most every `PROGRESS_S` seconds says how far PPO
is (issue 39: the page's step counter moved only on a refit or an evaluation). Every
`ACCOUNT_S` seconds a log line says where the worker's time went (PPO, refits, reads,
checkpoints, ...) and how long its longest slice took (a slice each rollout was logged
before: three quarters of a session's log lines).
"""

import dataclasses
import logging
import math
import time
from collections import defaultdict
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Future
from contextlib import contextmanager
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from groupwise.run.continuous import ContinuousRound
from groupwise.run.run import Run
from groupwise.storage import Database
from groupwise.storage.judgements import round_judgements
from groupwise.storage.phases import READY
from groupwise.storage.sessions import get_session
from groupwise.storage.timer import remaining
from groupwise.storage.training import add_point
from groupwise.worker import curve

if TYPE_CHECKING:
    from groupwise.worker.jobs import CutRound

log = logging.getLogger(__name__)

CHECKPOINT_S = 30.0
"""Seconds between a continuous round's mid-round checkpoints."""
ACCOUNT_S = 60.0
"""Seconds between the log lines that say where a continuous round's worker time went."""
STOP_POLL_S = 0.1
"""Least seconds between two reads, during a PPO rollout, of whether its round has ended
(a read is about a millisecond; an ended round's rollout stops within this)."""
HOLD_S = 60.0
"""Most seconds PPO waits for a round's end once the next round is cut (`holds`): a
person who stops short of the budget does not stop the agent for long."""
CUT_MARGIN_S = 1.0
"""Seconds added to the last cut's length when choosing how early to cut (a slice's
rollout in progress when the count rises, about a second on MuJoCo)."""
PACE_WINDOW = 6
"""The person's pace is the median gap between the round's last this many judgements."""
PROGRESS_S = 1.0
"""Least seconds between two points that only say how many PPO steps ran (one a rollout
on a slow env; a tiny env's rollouts would write dozens a second)."""


@dataclass
class ContinuousTraining:
    """One session's round being trained continuously in this worker."""

    session_id: str
    round: int
    run: Run
    continuous: ContinuousRound
    checkpointed: float
    """`time.monotonic()` of the last mid-round checkpoint."""
    pool_steps: int
    """PPO steps of the policy that played the round's pool (its oldest behaviour)."""
    trained_s: float = 0.0
    """Seconds this worker's PPO slices of the round took."""
    evaluated_s: float | None = None
    """`trained_s` at the last evaluation; None before the first."""
    eval_s: float = 0.0
    """Seconds the last finished evaluation took."""
    evaluating: "Future[float] | None" = None
    """The evaluation in the evaluator process (`curve.Evaluator`), until it is seen done."""
    pointed: float = 0.0
    """`time.monotonic()` of the last point this worker wrote."""
    spent: defaultdict[str, float] = dataclasses.field(default_factory=lambda: defaultdict(float))
    """Worker seconds by activity since `accounted` (`timed`): what is not PPO is PPO's
    loss, logged every `ACCOUNT_S` seconds."""
    accounted: float = dataclasses.field(default_factory=time.monotonic)
    staged: "CutRound | None" = None
    """The next round, cut before this round's budget ends it (`stage_due`); PPO waits
    while it is held (`holds`), and the round's training job opens it at once."""
    staged_at: float = 0.0
    """`time.monotonic()` when `staged` was cut."""
    staged_from: int = 0
    """The round's judgement count when `staged` was cut: PPO waits while it is not below."""
    cut_s: float | None = None
    """Seconds the session's last cut during a round took (carried into the next round):
    how early to cut (`comparisons_ahead`); before the first, the round's own pool's
    (its ``timings.json``, as `Offer.sample_s`)."""
    judged_at: list[float] = dataclasses.field(default_factory=list)
    """`time.monotonic()` of each rise of the round's judgement count seen by a slice: the
    person's pace."""
    counted: int = 0
    """The round's judgement count at the last slice."""
    longest_slice_s: float = 0.0
    """The longest slice since `accounted`: how long another session's job may have waited
    for one (its own round's end stops a slice, `round_ended`)."""
    declined: int | None = None
    """The round's judgement count at which a held stage ran out (`HOLD_S`): not staged
    again at that count."""

    @contextmanager
    def timed(self, activity: str) -> Iterator[None]:
        """Count the seconds of the block as `activity` in `spent`."""
        tick = time.perf_counter()
        try:
            yield
        finally:
            self.spent[activity] += time.perf_counter() - tick

    def account(self) -> None:
        """Log where the worker's time went since the last such line, once `ACCOUNT_S`
        seconds have passed (the rest of the wall time: other sessions, jobs, waiting)."""
        wall = time.monotonic() - self.accounted
        if wall < ACCOUNT_S:
            return
        self.spent["other"] = wall - sum(self.spent.values())
        parts = ", ".join(
            f"{name} {seconds:.1f} s ({seconds / wall:.0%})"
            for name, seconds in sorted(self.spent.items(), key=lambda item: -item[1])
        )
        log.info(
            "session %s round %d, the last %.0f s: %s; the longest slice %.1f s",
            self.session_id,
            self.round,
            wall,
            parts,
            self.longest_slice_s,
        )
        self.longest_slice_s = 0.0
        self.spent.clear()
        self.accounted = time.monotonic()


def train_slice(
    training: ContinuousTraining,
    db: Database,
    evaluator: Callable[[], curve.Evaluator],
    stage: "Callable[[ContinuousTraining], CutRound] | None" = None,
    budget: int = 0,
) -> bool:
    """Refit when due and train one rollout (module docstring); False when the round has
    no pairs yet, or PPO waits for the round's end. `evaluator` gives the
    process that evaluates the curve's points; `stage` cuts the next round
    (`jobs.cut_fresh`) once the round is within `comparisons_ahead` of its `budget`
    (0: none), or within a cut's length of its timer's end (`stage_due`; `stage` None:
    the round is the session's last)."""
    with training.timed("reads"), db.read() as s:
        keyed = round_judgements(s, training.session_id, training.round)
        left_s = remaining(get_session(s, training.session_id))
    with training.timed("refits"):
        refitted = training.continuous.update(keyed, time.monotonic())
    run = training.run
    if not len(run.dataset):  # PPO starts with the round's first pairs
        training.spent.clear()  # waiting for them is no loss of PPO's: not accounted
        training.accounted = time.monotonic()
        return False
    judged = len(keyed)
    if judged > training.counted:
        training.judged_at.append(time.monotonic())
    training.counted = judged
    cut_s = training.cut_s  # before the session's first cut: how long this round's pool took
    if cut_s is None and math.isfinite(training.continuous.offer.sample_s):
        cut_s = training.continuous.offer.sample_s
    ahead = comparisons_ahead(cut_s, training.judged_at)
    lead_s = (cut_s or 0.0) + CUT_MARGIN_S
    if stage is not None and stage_due(training, judged, budget, ahead, left_s, lead_s):
        tick = time.perf_counter()
        with training.timed("staging"):
            training.staged = stage(training)
        training.cut_s = time.perf_counter() - tick
        training.staged_at, training.staged_from = time.monotonic(), judged
        log.info(
            "session %s: round %d cut in %.1f s, %s",
            training.session_id,
            training.round + 1,
            training.cut_s,
            f"{left_s:.1f} s before round {training.round}'s timer ends"
            if left_s is not None and left_s <= lead_s
            else f"{budget - judged} comparison(s) before round {training.round}'s budget",
        )
    if training.staged is not None:
        if holds(training, judged):
            return False
        if time.monotonic() - training.staged_at >= HOLD_S:
            training.declined = judged
        training.staged = None  # PPO trains on; the round's end cuts the pool anew
    if refitted or training.evaluated_s is None:
        _point(training, db, evaluator, refit=refitted, evaluate=training.evaluated_s is None)
    tick = time.perf_counter()
    with training.timed("PPO"):
        whole = training.continuous.learn(
            run.ppo.rollout_steps, round_ended(training, db, STOP_POLL_S)
        )
    training.trained_s += time.perf_counter() - tick
    if not whole:  # the round ended meanwhile: its training job waits for nothing more
        log.info("session %s: round %d ended during a rollout", training.session_id, training.round)
        return True
    if _evaluation_due(training):
        _point(training, db, evaluator, refit=False, evaluate=True)
    elif time.monotonic() - training.pointed >= PROGRESS_S:
        _point(training, db, evaluator, refit=True, evaluate=False)
    if time.monotonic() - training.checkpointed >= CHECKPOINT_S:
        with training.timed("checkpoints"):
            run.save_mid_round(training.round)
        training.checkpointed = time.monotonic()
    training.account()
    return True


def comparisons_ahead(cut_s: float | None, judged_at: Sequence[float]) -> int:
    """How many comparisons before the round's budget to cut its next round: enough that a
    cut as long as the last one (`cut_s`, plus `CUT_MARGIN_S` for the slice in progress)
    is done when the person, at their pace so far (the median gap between the round's last
    `PACE_WINDOW` rises of its judgement count, `judged_at`), gives the last; 1 while
    either is unknown."""
    gaps = np.diff(np.asarray(judged_at[-PACE_WINDOW:], dtype=float))
    if cut_s is None or not len(gaps):
        return 1
    pace = max(float(np.median(gaps)), 1e-3)
    return max(1, math.ceil((cut_s + CUT_MARGIN_S) / pace))


def stage_due(
    training: ContinuousTraining,
    judged: int,
    budget: int,
    ahead: int = 1,
    left_s: float | None = None,
    lead_s: float = 0.0,
) -> bool:
    """Whether to cut the next round now: its end is in sight, `judged` within `ahead`
    comparisons of the round's `budget` (0: none; `comparisons_ahead`) or its timer's
    `left_s` seconds (None: not running) within `lead_s`, the seconds a cut takes; nothing
    is staged, and no stage ran out at this count (`declined`)."""
    if training.declined is not None and judged != training.declined:
        training.declined = None
    ending = (budget > 0 and budget - ahead <= judged < budget) or (
        left_s is not None and left_s <= lead_s
    )
    return ending and training.staged is None and training.declined is None


def holds(training: ContinuousTraining, judged: int) -> bool:
    """Whether PPO keeps waiting for the round's last comparisons, so that the staged pool
    stays the policy's: no judgement was undone below the count it was cut at (or the
    last came in and the round's job is on the way), the stage is younger than `HOLD_S`
    and no PPO step ran since it was cut."""
    staged = training.staged
    return (
        staged is not None
        and judged >= training.staged_from
        and time.monotonic() - training.staged_at < HOLD_S
        and staged.steps == training.run.agent.num_timesteps
    )


def round_ended(training: ContinuousTraining, db: Database, every_s: float) -> Callable[[], bool]:
    """Whether `training`'s round has ended (its session no longer ready in that round: the
    person, its budget or its timer ended it), read from the database at most every
    `every_s` seconds: PPO's `stop` in a slice (`ContinuousRound.learn`)."""
    read = time.monotonic()

    def ended() -> bool:
        nonlocal read
        now = time.monotonic()
        if now - read < every_s:
            return False
        read = now
        with db.read() as s:
            session = get_session(s, training.session_id)
            return session.phase != READY or session.round != training.round

    return ended


def _point(
    training: ContinuousTraining,
    db: Database,
    evaluator: Callable[[], curve.Evaluator],
    *,
    refit: bool,
    evaluate: bool,
) -> None:
    """Store a point of the learning curve: with `refit`, the steps and the fit now; then,
    with `evaluate`, hand the point with a snapshot of the greedy policy to the evaluator
    process, which stores it with the policy's true return when it has it
    (`curve.Evaluator`)."""
    run, report = training.run, training.continuous.report
    accuracy = None if report is None else report.validation_accuracy
    evaluating = evaluate and run.cfg.loop.eval_episodes > 0
    if refit or not evaluating:
        with training.timed("writes"), db.write() as s:
            add_point(
                s,
                training.session_id,
                round_index=training.round,
                ppo_steps=run.agent.num_timesteps,
                true_return=None,
                pairs=len(run.dataset),
                reward_val_accuracy=accuracy,
                pool_steps=training.pool_steps,
            )
    training.pointed = time.monotonic()
    if evaluate:
        training.evaluated_s = training.trained_s
    if evaluating:
        with training.timed("snapshots"):
            point = curve.snapshot(
                training.session_id, training.round, run, accuracy, training.pool_steps
            )
        training.evaluating = evaluator().submit(point)


def _evaluation_due(training: ContinuousTraining) -> bool:
    """Whether to evaluate the policy again (`worker.curve`): the last evaluation has
    finished and the slices have trained long enough since."""
    if training.evaluating is not None:
        if not training.evaluating.done():
            return False
        try:
            training.eval_s = training.evaluating.result()
        except Exception:
            log.exception("session %s: evaluating the policy failed", training.session_id)
        training.evaluating = None
    since = training.trained_s - (training.evaluated_s or 0.0)
    return since >= max(curve.EVAL_MIN_S, curve.EVAL_COST * training.eval_s)
