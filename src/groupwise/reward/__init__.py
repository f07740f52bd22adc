"""The reward model (SPEC §3): an ensemble of MLPs over [obs ; act], trained Bradley–Terry."""

from groupwise.reward.bradley_terry import FitReport, fit, validation_mask
from groupwise.reward.ensemble import RewardEnsemble
from groupwise.reward.network import ACTIVATIONS, RewardNet, RunningNorm, StackedMLP

__all__ = [
    "ACTIVATIONS",
    "FitReport",
    "RewardEnsemble",
    "RewardNet",
    "RunningNorm",
    "StackedMLP",
    "fit",
    "validation_mask",
]
