"""Temporal crops (QPA) and confident pseudo-labels (SURF) as Bradley–Terry objectives."""

import numpy as np
import pytest
import torch

from groupwise.config import RewardConfig
from groupwise.episodes.fragments import Fragment
from groupwise.preferences.dataset import PreferenceDataset
from groupwise.reward import RewardEnsemble, fit
from groupwise.reward.augment import (
    PseudoLabels,
    TemporalCrops,
    confident_labels,
    crop_masks,
)
from groupwise.reward.objective import BradleyTerryLoss
from groupwise.reward.round_fit import objective_of

OBS_DIM, ACT_DIM, LENGTH = 4, 2, 10


def _fragments(n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """n random-walk fragments (obs, acts, true return); the true reward is obs[0]."""
    obs = (rng.normal(size=(n, 1, OBS_DIM)) + np.cumsum(
        rng.normal(scale=0.3, size=(n, LENGTH, OBS_DIM)), axis=1)).astype(np.float32)  # fmt: skip
    acts = rng.uniform(-1, 1, size=(n, LENGTH, ACT_DIM)).astype(np.float32)
    return obs, acts, obs[..., 0].sum(axis=1).astype(np.float64)


def _dataset(n_pairs: int, seed: int = 0) -> PreferenceDataset:
    obs, acts, returns = _fragments(2 * n_pairs, np.random.default_rng(seed))
    pairs = np.arange(2 * n_pairs).reshape(n_pairs, 2)
    labels = (returns[pairs[:, 0]] > returns[pairs[:, 1]]).astype(np.float32)
    return PreferenceDataset(obs, acts, returns, pairs, labels)


def test_crops_are_contiguous_equally_long_within_the_share_and_drawn_apart():
    masks = crop_masks(50, (3, 4), 50, (0.7, 0.9), np.random.default_rng(0))
    assert masks.shape == (50, 3, 4, 2, 50)
    sizes = masks.sum(axis=-1)  # (50, 3, 4, 2)
    assert (sizes[..., 0] == sizes[..., 1]).all()  # a's crop and b's are equally long
    assert sizes.min() >= 35 and sizes.max() <= 45  # QPA's 35-45 of 50
    starts = masks.argmax(axis=-1)
    ends = masks.shape[-1] - masks[..., ::-1].argmax(axis=-1)
    assert ((ends - starts) == sizes).all()  # one stretch each: no gaps
    assert (starts[..., 0] != starts[..., 1]).any()  # offsets drawn for each fragment
    assert len(np.unique(sizes)) > 5


def test_crops_keep_the_label_and_each_fragment_its_own_steps():
    # a pays 1 on every step, b pays 0 on every step except a huge one at its last step
    rewards = torch.zeros(1, 1, 2, 10)
    rewards[0, 0, 0] = 1.0
    rewards[0, 0, 1, -1] = -100.0
    masks = torch.from_numpy(crop_masks(200, (1, 1), 10, (0.7, 0.9), np.random.default_rng(1)))
    cropped = (rewards * masks).sum(-1)  # as TemporalCrops scores them
    assert (cropped[..., 0] == masks[..., 0, :].sum(-1)).all()  # a's crops sum a's steps
    assert set(cropped[..., 1].unique().tolist()) <= {0.0, -100.0}  # b's only b's
    low = TemporalCrops(200).loss(None, rewards, torch.ones(1, 1), np.random.default_rng(1))
    high = TemporalCrops(200).loss(None, rewards, torch.zeros(1, 1), np.random.default_rng(1))
    assert low.item() < 1e-3 < 7.0 < high.item()  # the label a ≻ b is kept by every crop


def test_one_whole_crop_is_the_plain_bradley_terry_loss():
    rng = np.random.default_rng(2)
    rewards = torch.from_numpy(rng.normal(size=(3, 5, 2, 8)).astype(np.float32))
    labels = torch.from_numpy(rng.integers(0, 2, size=(3, 5)).astype(np.float32))
    whole = TemporalCrops(1, (1.0, 1.0)).loss(None, rewards, labels, rng)
    plain = BradleyTerryLoss().loss(None, rewards, labels, rng)
    torch.testing.assert_close(whole, plain)


def test_bad_crops_are_refused():
    with pytest.raises(ValueError):
        TemporalCrops(0)
    with pytest.raises(ValueError):
        TemporalCrops(5, (0.9, 0.7))


def test_pseudo_labels_only_above_the_confidence_threshold():
    p = torch.tensor([0.99, 0.96, 0.95, 0.94, 0.5, 0.06, 0.04, 0.0])
    labels, mask = confident_labels(p, 0.95)
    assert mask.tolist() == [1, 1, 1, 0, 0, 0, 1, 1]
    assert labels[mask.bool()].tolist() == [1, 1, 1, 0, 0]
    with pytest.raises(ValueError):
        confident_labels(p, 0.4)


def test_pseudo_labelled_pairs_add_loss_only_where_the_members_are_sure():
    cfg = RewardConfig()
    data = _dataset(100)
    ensemble = RewardEnsemble(OBS_DIM, ACT_DIM, cfg, np.random.default_rng(0))
    fit(ensemble, data, cfg, np.random.default_rng(0), epochs=5)  # a reward that is sure
    obs, acts, _ = _fragments(40, np.random.default_rng(9))
    rewards = torch.zeros(3, 4, 2, LENGTH)  # the labelled minibatch: log 2 a pair
    labels = torch.from_numpy(data.labels[:4]).expand(3, 4)
    plain = BradleyTerryLoss().loss(ensemble.net, rewards, labels, np.random.default_rng(5))

    def with_threshold(threshold: float) -> torch.Tensor:
        objective = PseudoLabels(obs, acts, ensemble.features, threshold)
        return objective.loss(ensemble.net, rewards, labels, np.random.default_rng(5))

    never = with_threshold(1.0)  # no pair is that sure: nothing added
    torch.testing.assert_close(never, plain)
    sure = with_threshold(0.95)
    assert (sure >= plain).all() and (sure > plain).any()  # sure of some: their loss added
    assert (with_threshold(0.5) >= sure).all()  # every pair labelled: more loss, not less


def test_the_config_composes_the_objective():
    ensemble = RewardEnsemble(OBS_DIM, ACT_DIM, RewardConfig(), np.random.default_rng(0))
    obs, acts, _ = _fragments(3, np.random.default_rng(0))
    pool = [Fragment(o, a, np.zeros(LENGTH), 0, 0, 0) for o, a in zip(obs, acts, strict=True)]
    assert isinstance(objective_of(RewardConfig(), ensemble, pool), BradleyTerryLoss)
    assert isinstance(objective_of(RewardConfig(crops=20), ensemble, pool), TemporalCrops)
    both = objective_of(RewardConfig(crops=20, pseudo_labels=0.95), ensemble, pool)
    assert isinstance(both, PseudoLabels) and isinstance(both.inner, TemporalCrops)
    assert isinstance(
        objective_of(RewardConfig(pseudo_labels=0.95), ensemble, pool[:1]), BradleyTerryLoss
    )


@pytest.mark.parametrize("cfg", [RewardConfig(crops=20), RewardConfig(crops=4, pseudo_labels=0.95)])
def test_a_reward_fitted_with_the_remedies_still_learns(cfg):
    data = _dataset(200)
    ensemble = RewardEnsemble(OBS_DIM, ACT_DIM, cfg, np.random.default_rng(0))
    obs, acts, _ = _fragments(60, np.random.default_rng(7))
    pool = [Fragment(o, a, np.zeros(LENGTH), 0, 0, 0) for o, a in zip(obs, acts, strict=True)]
    report = fit(
        ensemble,
        data,
        cfg,
        np.random.default_rng(0),
        8,
        objective=objective_of(cfg, ensemble, pool),
    )
    assert report.validation_accuracy > 0.85
    fresh_obs, fresh_acts, truth = _fragments(300, np.random.default_rng(123))
    predicted = ensemble.returns(fresh_obs, fresh_acts).mean(axis=1)
    assert np.corrcoef(predicted, truth)[0, 1] > 0.85
