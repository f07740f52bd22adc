"""Teachers and the simulated decision-makers, registered by name (SPEC §7).

A decision-maker (DM) is a query strategy (`groupwise.query.strategies`) answered by a
teacher: `Feedback(queries, teacher)`. "pairwise", "groupwise" and "interactive" are the
paper's three DMs ("interactive" as the paper's reference code walks; "interactive-mean" as
its text describes; "interactive-distinct" and "interactive-clear" are walks of ours, see
`query.interactive`); "<dm>-<imperfection>" (e.g. "groupwise-myopic", "pairwise-mistake")
answers the same queries with a B-Pref-style imperfect teacher (`imperfect.TEACHERS`:
myopic, mistake, skip, equal). A person answers through the web page
(`groupwise.worker.web_teacher.WebTeacher`).
"""

import dataclasses
from collections.abc import Callable

from groupwise.config import RunConfig, TeacherConfig
from groupwise.query.strategies import (
    GroupSuggestions,
    InteractiveWalk,
    PairwiseQueries,
    QueryStrategy,
)
from groupwise.teachers.base import Feedback, FeedbackSource, Teacher
from groupwise.teachers.calibration import CalibratedTeacher, calibrated_noise_sd
from groupwise.teachers.group_decision import Perception, SimulatedTeacher
from groupwise.teachers.imperfect import TEACHERS, Imperfection
from groupwise.teachers.pairwise import PairwiseTeacher
from groupwise.types import FloatArray


def _imperfection(cfg: TeacherConfig) -> Imperfection:
    return Imperfection(
        gamma=cfg.gamma,
        mistake=cfg.mistake,
        skip_quantile=cfg.skip_quantile,
        equal_fraction=cfg.equal_fraction,
    )


def _perceived_noise(cfg: TeacherConfig) -> Callable[[FloatArray], float] | None:
    """A calibrated teacher's per-behaviour noise sd for a pool's true returns (what it
    sees as clear is relative to the noise it has on that pool), or None for SPEC §7's
    fixed σ."""
    error = cfg.label_error
    if error is None:
        return None
    return lambda returns: calibrated_noise_sd(returns, error)


STRATEGIES: dict[str, Callable[[RunConfig], QueryStrategy]] = {
    "pairwise": lambda run: PairwiseQueries(candidates=run.loop.candidate_pairs),
    "groupwise": lambda run: GroupSuggestions(tree=run.tree, max_group=run.loop.max_group_size),
    # the paper's reference code: sum of true returns, every level-1/2 node (padding nodes
    # over single leaves included), two passes
    "interactive": lambda run: InteractiveWalk(
        tree=run.tree, rank="sum", min_group=1, max_group=UNLIMITED, padding=True, passes=2
    ),
    # the paper's text: mean true return, groups of 2-8, one pass
    "interactive-mean": lambda run: InteractiveWalk(
        tree=run.tree, max_group=run.loop.max_group_size
    ),
    "interactive-distinct": lambda run: InteractiveWalk(
        tree=run.tree,
        max_group=run.loop.max_group_size,
        min_gap=run.teacher.interactive_gap * run.loop.fragment_length * run.teacher.noise_sigma,
    ),
    # ours: only clearly different groups, passes until the budget is used
    "interactive-clear": lambda run: InteractiveWalk(
        tree=run.tree,
        max_group=run.loop.max_group_size,
        clear=run.teacher.interactive_clear,
        noise_sd=run.loop.fragment_length * run.teacher.noise_sigma,
        perceived_noise=_perceived_noise(run.teacher),
    ),
}
"""How each DM chooses its queries (the interactive walks: `groupwise.query.interactive`)."""

UNLIMITED = 2**31 - 1
"""A group-size limit that limits nothing (the reference code's Interactive-DM)."""


def _dm(
    strategy: str, teacher: Callable[[TeacherConfig], Teacher]
) -> Callable[[RunConfig], Feedback]:
    """The DM `strategy` answered by `teacher`, calibrated to `TeacherConfig.label_error`
    when that is set (its σ then set per pool: `calibration.CalibratedTeacher`)."""

    def build(run: RunConfig) -> Feedback:
        cfg = run.teacher
        answer = teacher(cfg)
        if cfg.label_error is not None:
            answer = CalibratedTeacher(
                lambda sigma: teacher(dataclasses.replace(cfg, noise_sigma=sigma)),
                cfg.label_error,
            )
        return Feedback(STRATEGIES[strategy](run), answer)

    return build


def _paper_teacher(cfg: TeacherConfig) -> Teacher:
    return SimulatedTeacher(Perception(cfg.noise_sigma))


def _imperfect(kind: str) -> Callable[[TeacherConfig], Teacher]:
    return lambda cfg: TEACHERS[kind](cfg.noise_sigma, _imperfection(cfg))


DECISION_MAKERS: dict[str, Callable[[RunConfig], Feedback]] = {
    "pairwise": _dm("pairwise", lambda cfg: PairwiseTeacher(sigma=cfg.noise_sigma)),
    # the reference code's pairwise labels: Boltzmann-rational, temperature 1
    "pairwise-boltzmann": _dm(
        "pairwise", lambda cfg: PairwiseTeacher(sigma=cfg.noise_sigma, beta=1.0)
    ),
    "groupwise": _dm("groupwise", _paper_teacher),
    "interactive": _dm("interactive", _paper_teacher),
    "interactive-mean": _dm("interactive-mean", _paper_teacher),
    "interactive-distinct": _dm("interactive-distinct", _paper_teacher),
    "interactive-clear": _dm("interactive-clear", _paper_teacher),
    **{
        f"{dm}-{kind}": _dm(dm, _imperfect(kind))
        for dm in ("pairwise", "groupwise", "interactive")
        for kind in TEACHERS
    },
}
"""Every registered decision-maker, by name (the study's `--dms`), built from a run's config."""

__all__ = [
    "DECISION_MAKERS",
    "STRATEGIES",
    "Feedback",
    "FeedbackSource",
    "PairwiseTeacher",
    "Perception",
    "SimulatedTeacher",
    "Teacher",
]
