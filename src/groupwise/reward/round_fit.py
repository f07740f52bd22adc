"""A round's reward fit with the objective its `RewardConfig` asks for (issue 41): SPEC §3's
Bradley–Terry loss, or with temporal crops and confident pseudo-labels (`reward.augment`),
around `bradley_terry.fit`. With those fields off it is exactly `fit`.

    report = fit_round(ensemble, dataset, cfg, rng, epochs, latest=pool)
"""

from collections.abc import Sequence

import numpy as np

from groupwise.config import RewardConfig
from groupwise.episodes.fragments import Fragment
from groupwise.preferences.dataset import PreferenceDataset
from groupwise.reward.augment import PseudoLabels, TemporalCrops
from groupwise.reward.bradley_terry import FitReport, fit
from groupwise.reward.ensemble import RewardEnsemble
from groupwise.reward.objective import BradleyTerryLoss, Objective


def objective_of(
    cfg: RewardConfig, ensemble: RewardEnsemble, unlabelled: Sequence[Fragment]
) -> Objective:
    """The loss `cfg` asks for: Bradley–Terry over `cfg.crops` temporal crops (or the whole
    pairs), plus confidently pseudo-labelled pairs of `unlabelled` when `cfg.pseudo_labels`
    is set and there are two such fragments of the dataset's length."""
    objective: Objective = TemporalCrops(cfg.crops) if cfg.crops else BradleyTerryLoss()
    if cfg.pseudo_labels is None or len(unlabelled) < 2:
        return objective
    obs = np.stack([f.obs for f in unlabelled])
    acts = np.stack([f.acts for f in unlabelled])
    return PseudoLabels(obs, acts, ensemble.features, cfg.pseudo_labels, objective)


def fit_round(
    ensemble: RewardEnsemble,
    dataset: PreferenceDataset,
    cfg: RewardConfig,
    rng: np.random.Generator,
    epochs: int,
    latest: Sequence[Fragment],
) -> FitReport:
    """A round's fit of `ensemble` on the whole `dataset` (`bradley_terry.fit`), `epochs`
    epochs, with `objective_of(cfg, …)`; `latest` are the round's pool behaviours, the
    unlabelled pairs' fragments."""
    return fit(ensemble, dataset, cfg, rng, epochs, objective=objective_of(cfg, ensemble, latest))
