"""A whole run without a person: `groupwise train`, the simulation study and the library.

`round_plan` says what each round asks (comparisons, PPO steps; a last row without
feedback when `final_steps` is set); `run_rounds` runs the rounds not run yet
(`round.run_round`, `round.train_frozen`); `run_session` does that for a fresh or resumed
`Run` in a directory, answered by a simulated decision-maker from `DECISION_MAKERS`.
"""

import logging
from pathlib import Path

from groupwise.config import LoopConfig, RunConfig
from groupwise.query.schedule import comparisons_per_round
from groupwise.run.continuous import continuous_round
from groupwise.run.final import choose_takeaway, publish_agent
from groupwise.run.pretrain import before_first_round
from groupwise.run.progress import CallbackList, ProgressBars, RunCallback, as_callback
from groupwise.run.records import RoundRecord
from groupwise.run.round import run_round, train_frozen
from groupwise.run.run import Run
from groupwise.run.takeaway import TakeawayChoice, TakeawayConfig
from groupwise.teachers import DECISION_MAKERS, Feedback

log = logging.getLogger(__name__)


def round_plan(loop: LoopConfig) -> list[tuple[int, int]]:
    """(comparisons, PPO steps) of each round; a last (0, final_steps) row when set."""
    schedule = comparisons_per_round(
        loop.comparisons, loop.rounds, loop.initial_fraction, loop.schedule
    )
    plan = [(n, loop.steps // loop.rounds) for n in schedule]
    if loop.final_steps > 0:
        plan.append((0, loop.final_steps))
    return plan


def feedback_of(cfg: RunConfig) -> Feedback:
    """The simulated decision-maker `cfg.loop.decision_maker`, from
    `groupwise.teachers.DECISION_MAKERS`.

    Raises:
        ValueError: no such decision-maker (e.g. "human": a person answers app sessions).
    """
    if cfg.loop.decision_maker not in DECISION_MAKERS:
        raise ValueError(
            f"no simulated decision-maker {cfg.loop.decision_maker!r} (a person answers an app "
            f"session's rounds); choose from {', '.join(DECISION_MAKERS)}"
        )
    return DECISION_MAKERS[cfg.loop.decision_maker](cfg)


def run_rounds(
    run: Run, feedback: Feedback, callback: RunCallback | None = None
) -> list[RoundRecord]:
    """Run the rounds of `round_plan` not run yet, each committed when the run has a
    directory; the one round driver of `run_session`, the case studies and
    `PreferenceComparisons.train`. With `training.mode` "continuous" a feedback round's PPO
    runs while its timed teacher answers (`run.continuous`), not the plan's steps. A run
    whose agent has not trained yet first runs the config's setup hooks
    (`run.pretrain.setup_hooks`: state-entropy pre-training when asked)."""
    plan = round_plan(run.cfg.loop)
    before_first_round(run, callback)
    staged = None  # a continuous round's next round, cut during its last answer
    while run.next_round < len(plan):
        budget, steps = plan[run.next_round]
        if budget == 0:  # the final row: PPO on the frozen reward
            train_frozen(run, steps, callback=callback)
        elif run.cfg.training.mode == "continuous":  # PPO's steps come from the clock
            following = plan[run.next_round + 1][0] if run.next_round + 1 < len(plan) else 0
            _, staged = continuous_round(
                run, feedback, budget, callback, staged=staged, following=following or None
            )
        else:
            run_round(run, feedback, budget, steps, callback)
    return run.records


def run_session(
    cfg: RunConfig,
    out: Path,
    resume: bool = False,
    show_progress: bool = True,
    feedback: Feedback | None = None,
    callback: RunCallback | None = None,
    takeaway: TakeawayConfig | None = None,
) -> list[RoundRecord]:
    """Run (or continue, with `resume`) a whole RLHF run, writing it into `out`.

    Writes `config.json`, `rounds.csv` (rewritten after every round), TensorBoard logs and
    one checkpoint per round. Rounds 0 … R−1 gather feedback from `feedback` (default: the
    decision-maker `cfg.loop.decision_maker`); when `final_steps` > 0 a last row (round R, no
    comparisons) trains PPO further on the frozen learned reward. With `takeaway` the run
    then hands over an agent (`hand_over`: ``takeaway.json``, ``agent.zip``, ``agent.json``).

    Raises:
        ConfigMismatchError: `resume` and `out` was written by another configuration.
        ValueError: unknown env or decision-maker.
    """
    feedback = feedback or feedback_of(cfg)
    with Run.create(cfg, out, check=resume) as run:
        if resume:
            run.restore()
        callbacks = [_RoundLog(), as_callback(callback)]
        bars = None
        if show_progress:
            bars = ProgressBars(len(round_plan(cfg.loop)), run.next_round, cfg.loop.env)
            callbacks.append(bars)
        try:
            records = run_rounds(run, feedback, CallbackList(callbacks))
            if takeaway is not None:
                hand_over(run, feedback, takeaway, CallbackList(callbacks))
            return records
        finally:
            if bars is not None:
                bars.close()


def hand_over(
    run: Run, feedback: Feedback, cfg: TakeawayConfig, callback: RunCallback | None = None
) -> TakeawayChoice:
    """After a headless run's last round: the round `feedback`'s teacher prefers
    (`final.choose_takeaway`, ``takeaway.json``) packed as the take-away agent
    (``agent.zip`` and ``agent.json``, no videos)."""
    choice = choose_takeaway(run, feedback.teacher, cfg, callback)
    frozen = {run.cfg.loop.rounds} if run.cfg.loop.final_steps > 0 else set()
    publish_agent(run, frozen, callback=callback, choice=choice, video=False, round_videos=False)
    log.info("%s", choice.describe())
    return choice


class _RoundLog(RunCallback):
    def on_round_end(self, record: RoundRecord) -> None:
        log.info(
            "round %d: %d pairs in total, label error %.3f, reward acc %.3f, true return %.2f",
            record.round,
            record.pairs_total,
            record.label_error_rate_total,
            record.reward_accuracy,
            record.true_return_mean,
        )
