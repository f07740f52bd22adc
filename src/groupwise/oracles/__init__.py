"""Simulated decision-makers, registered by name (SPEC §7).

"pairwise", "groupwise" and "interactive" are the paper's three DMs; "interactive-distinct" is
the Interactive-DM that compares only groups at least `LoopConfig.interactive_gap` noise sds
apart in mean true return (beyond the spec, see `interactive.py`); "<dm>-<imperfection>"
(e.g. "groupwise-myopic", "pairwise-mistake") answers the same queries with a B-Pref-style
imperfect teacher (`imperfect.TEACHERS`: myopic, mistake, skip, equal).
"""

from collections.abc import Callable

from groupwise.config import LoopConfig
from groupwise.oracles.base import Oracle
from groupwise.oracles.group_decision import Perception, Teacher
from groupwise.oracles.groupwise import GroupwiseDM
from groupwise.oracles.imperfect import TEACHERS, Imperfection, TeacherPairwiseDM
from groupwise.oracles.interactive import InteractiveDM
from groupwise.oracles.pairwise import PairwiseDM


def _imperfection(cfg: LoopConfig) -> Imperfection:
    return Imperfection(
        gamma=cfg.teacher_gamma,
        mistake=cfg.teacher_mistake,
        skip_quantile=cfg.teacher_skip_quantile,
        equal_fraction=cfg.teacher_equal_fraction,
    )


def _teacher(cfg: LoopConfig) -> Teacher:
    return Teacher(Perception(cfg.noise_sigma))


_QUERIES: dict[str, Callable[[LoopConfig, Teacher], Oracle]] = {
    "pairwise": lambda cfg, t: TeacherPairwiseDM(t, candidates=cfg.candidate_pairs),
    "groupwise": lambda cfg, t: GroupwiseDM(t, max_group=cfg.max_group_size),
    "interactive": lambda cfg, t: InteractiveDM(t, max_group=cfg.max_group_size),
}
"""How each DM chooses its queries, given the teacher that answers them."""


def _imperfect(dm: str, imperfection: str) -> Callable[[LoopConfig], Oracle]:
    def make(cfg: LoopConfig) -> Oracle:
        teacher = TEACHERS[imperfection](cfg.noise_sigma, _imperfection(cfg))
        return _QUERIES[dm](cfg, teacher)

    return make


ORACLES: dict[str, Callable[[LoopConfig], Oracle]] = {
    "pairwise": lambda cfg: PairwiseDM(sigma=cfg.noise_sigma, candidates=cfg.candidate_pairs),
    "groupwise": lambda cfg: _QUERIES["groupwise"](cfg, _teacher(cfg)),
    "interactive": lambda cfg: _QUERIES["interactive"](cfg, _teacher(cfg)),
    "interactive-distinct": lambda cfg: InteractiveDM(
        _teacher(cfg),
        max_group=cfg.max_group_size,
        min_gap=cfg.interactive_gap * cfg.fragment_length * cfg.noise_sigma,
    ),
    **{f"{dm}-{kind}": _imperfect(dm, kind) for dm in _QUERIES for kind in TEACHERS},
}

__all__ = [
    "ORACLES",
    "GroupwiseDM",
    "InteractiveDM",
    "Oracle",
    "PairwiseDM",
    "Perception",
    "Teacher",
    "TeacherPairwiseDM",
]
