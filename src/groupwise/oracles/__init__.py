"""Simulated decision-makers, registered by name (SPEC §7)."""

from collections.abc import Callable

from groupwise.config import LoopConfig
from groupwise.oracles.base import Oracle
from groupwise.oracles.pairwise import PairwiseDM

ORACLES: dict[str, Callable[[LoopConfig], Oracle]] = {
    "pairwise": lambda cfg: PairwiseDM(sigma=cfg.noise_sigma, candidates=cfg.candidate_pairs),
}

__all__ = ["ORACLES", "Oracle", "PairwiseDM"]
