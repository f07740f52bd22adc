"""A round's reward fit, composed from its `RewardConfig` (issue 41): the objective
(`objective_of`: SPEC §3's Bradley–Terry loss, or with temporal crops and confident
pseudo-labels, `reward.augment`) and the re-initialisation rule (`reward.reset`), around
`bradley_terry.fit`. With every research field off it is exactly `fit`.

    report = fit_round(ensemble, dataset, cfg, rng, epochs, round_index=r, latest=pool)
"""

import logging
from collections.abc import Sequence

import numpy as np

from groupwise.config import RewardConfig
from groupwise.episodes.fragments import Fragment
from groupwise.preferences.dataset import PreferenceDataset
from groupwise.reward.augment import PseudoLabels, TemporalCrops
from groupwise.reward.bradley_terry import FitReport, fit
from groupwise.reward.ensemble import RewardEnsemble
from groupwise.reward.objective import BradleyTerryLoss, Objective
from groupwise.reward.reset import ResetRule

log = logging.getLogger(__name__)


def objective_of(
    cfg: RewardConfig, ensemble: RewardEnsemble, unlabelled: Sequence[Fragment]
) -> Objective:
    """The loss `cfg` asks for: Bradley–Terry over `cfg.crops` temporal crops (or the whole
    pairs), plus confidently pseudo-labelled pairs of `unlabelled` when `cfg.pseudo_labels`
    is set and there are two such fragments of the dataset's length."""
    objective: Objective = TemporalCrops(cfg.crops) if cfg.crops else BradleyTerryLoss()
    if cfg.pseudo_labels is None or len(unlabelled) < 2:
        return objective
    obs, acts = _stacked(unlabelled)
    return PseudoLabels(obs, acts, ensemble.features, cfg.pseudo_labels, objective)


def fit_round(
    ensemble: RewardEnsemble,
    dataset: PreferenceDataset,
    cfg: RewardConfig,
    rng: np.random.Generator,
    epochs: int,
    *,
    round_index: int,
    latest: Sequence[Fragment],
) -> FitReport:
    """Round `round_index`'s fit of `ensemble` on the whole `dataset` (`bradley_terry.fit`),
    `epochs` epochs; `latest` are the round's pool behaviours (the unlabelled pairs'
    fragments and the agent's newest behaviour). When `cfg`'s reset rule fires the members
    are first drawn afresh from `rng` and train at least round 0's epochs."""
    rule = ResetRule(cfg.reset_every, cfg.reset_margin)
    if rule.every is not None or rule.margin is not None:
        obs, acts = _stacked(latest)
        reason = rule.reason(round_index, ensemble, dataset, obs, acts)
        if reason is not None:
            ensemble.reinitialise(rng)
            epochs = max(epochs, round(cfg.epochs * cfg.initial_epoch_multiplier))
            log.info("round %d: reward ensemble reset (%s), %d epochs", round_index, reason, epochs)
    return fit(ensemble, dataset, cfg, rng, epochs, objective=objective_of(cfg, ensemble, latest))


def _stacked(fragments: Sequence[Fragment]) -> tuple[np.ndarray, np.ndarray]:
    """(obs (N, L, obs_dim), acts (N, L, act_dim)) of equally long fragments; N may be 0."""
    if not fragments:
        return np.zeros((0, 0, 0), np.float32), np.zeros((0, 0, 0), np.float32)
    return np.stack([f.obs for f in fragments]), np.stack([f.acts for f in fragments])
