"""Re-initialising the reward ensemble (PoLiCER): the schedule, the signal, and the refit."""

import copy

import numpy as np
import pytest
import torch

from groupwise.config import RewardConfig
from groupwise.episodes.fragments import Fragment
from groupwise.preferences.dataset import PreferenceDataset
from groupwise.reward import RewardEnsemble, fit
from groupwise.reward.reset import ResetRule, overestimation, preferred
from groupwise.reward.round_fit import fit_round

OBS_DIM, ACT_DIM, LENGTH = 1, 1, 5
CFG = RewardConfig(use_actions=False)


def _level(levels) -> tuple[np.ndarray, np.ndarray]:
    """Fragments standing still at each of `levels` (obs, acts)."""
    obs = np.repeat(np.asarray(levels, np.float32)[:, None, None], LENGTH, axis=1)
    return obs, np.zeros((len(levels), LENGTH, ACT_DIM), np.float32)


def _higher_is_better(n_pairs: int = 60, seed: int = 0) -> PreferenceDataset:
    """Pairs of fragments at levels in [−1, 1], the higher one preferred."""
    levels = np.random.default_rng(seed).uniform(-1, 1, size=2 * n_pairs)
    obs, acts = _level(levels)
    pairs = np.arange(2 * n_pairs).reshape(n_pairs, 2)
    labels = (levels[pairs[:, 0]] > levels[pairs[:, 1]]).astype(np.float32)
    return PreferenceDataset(obs, acts, levels * LENGTH, pairs, labels)


def _fitted(data: PreferenceDataset) -> RewardEnsemble:
    ensemble = RewardEnsemble(OBS_DIM, ACT_DIM, CFG, np.random.default_rng(0))
    fit(ensemble, data, CFG, np.random.default_rng(0), epochs=10)
    return ensemble


def _weights(ensemble: RewardEnsemble) -> list[torch.Tensor]:
    return [p.detach().clone() for p in ensemble.net.mlp.parameters()]


def test_the_schedule_resets_every_k_rounds_but_never_round_0():
    data = _higher_is_better(5)
    ensemble = RewardEnsemble(OBS_DIM, ACT_DIM, CFG, np.random.default_rng(0))
    rule = ResetRule(every=2)
    obs, acts = _level([0.0])
    fired = [rule.reason(r, ensemble, data, obs, acts) for r in range(6)]
    assert fired == [None, None, "schedule", None, "schedule", None]
    assert ResetRule().reason(4, ensemble, data, obs, acts) is None
    with pytest.raises(ValueError):
        ResetRule(every=0)


def test_preferred_behaviours_are_the_winning_sides():
    data = PreferenceDataset(
        *_level([0, 1, 2, 3]), np.zeros(4), np.array([[0, 1], [2, 3], [1, 3]]),
        np.array([1.0, 0.0, 0.5], np.float32),
    )  # fmt: skip
    assert preferred(data).tolist() == [0, 3]


def test_the_signal_fires_when_the_reward_pays_the_agent_more_than_the_preferred():
    data = _higher_is_better()
    ensemble = _fitted(data)  # learnt: the higher, the better
    above, below = _level([3.0, 3.0]), _level([-1.0, -1.0])  # the agent beyond any judged
    assert overestimation(ensemble, data, *above) > 0.5
    assert overestimation(ensemble, data, *below) < 0
    rule = ResetRule(margin=0.5)
    assert rule.reason(1, ensemble, data, *above) == "signal"
    assert rule.reason(1, ensemble, data, *below) is None


def test_a_reset_refits_fresh_weights_on_the_whole_dataset():
    data = _higher_is_better()
    cfg = RewardConfig(use_actions=False, reset_every=1)
    ensemble = _fitted(data)
    before = _weights(ensemble)
    expected = copy.deepcopy(ensemble)
    rng = np.random.default_rng(4)
    expected.reinitialise(np.random.default_rng(4))
    fresh = _weights(expected)
    epochs = round(cfg.epochs * cfg.initial_epoch_multiplier)  # a fresh net: round 0's epochs
    obs, acts = _level([0.0, 1.0])
    pool = [Fragment(o, a, np.zeros(LENGTH), 0, 0, 0) for o, a in zip(obs, acts, strict=True)]
    report = fit_round(ensemble, data, cfg, rng, cfg.epochs, round_index=1, latest=pool)
    fit(expected, data, cfg, _after_init(4), epochs)
    assert report.n_pairs == len(data) and report.epochs == epochs
    assert all(not torch.equal(a, b) for a, b in zip(before, fresh, strict=True))
    for got, want in zip(_weights(ensemble), _weights(expected), strict=True):
        torch.testing.assert_close(got, want, rtol=0, atol=0)


def _after_init(seed: int) -> np.random.Generator:
    """The generator `fit_round` fits with after drawing the fresh weights from it."""
    rng = np.random.default_rng(seed)
    rng.integers(0, 2**63 - 1)  # what `RewardEnsemble.reinitialise` draws
    return rng


def test_without_a_rule_the_round_fit_is_the_plain_fit():
    data = _higher_is_better()
    ensemble, plain = _fitted(data), _fitted(data)
    fit_round(ensemble, data, CFG, np.random.default_rng(2), 3, round_index=2, latest=[])
    fit(plain, data, CFG, np.random.default_rng(2), 3)
    for got, want in zip(_weights(ensemble), _weights(plain), strict=True):
        torch.testing.assert_close(got, want, rtol=0, atol=0)
