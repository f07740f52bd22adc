import math

import numpy as np
import pytest

from groupwise.config import RewardConfig
from groupwise.preferences.dataset import PreferenceDataset
from groupwise.reward import RewardEnsemble, fit, validation_mask

OBS_DIM, ACT_DIM, LENGTH = 4, 2, 10
CFG = RewardConfig()


def fragments(n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """n random-walk fragments (obs, acts, true return); the true reward is obs[0]."""
    start = rng.normal(size=(n, 1, OBS_DIM))
    walk = np.cumsum(rng.normal(scale=0.3, size=(n, LENGTH, OBS_DIM)), axis=1)
    obs = (start + walk).astype(np.float32)
    acts = rng.uniform(-1, 1, size=(n, LENGTH, ACT_DIM)).astype(np.float32)
    return obs, acts, obs[..., 0].sum(axis=1).astype(np.float64)


def make_dataset(n_pairs: int, seed: int = 0, tie: bool = False) -> PreferenceDataset:
    """2·n_pairs fresh fragments paired off, labelled by the true return (or all equal)."""
    obs, acts, returns = fragments(2 * n_pairs, np.random.default_rng(seed))
    pairs = np.arange(2 * n_pairs).reshape(n_pairs, 2)
    labels = (returns[pairs[:, 0]] > returns[pairs[:, 1]]).astype(np.float32)
    if tie:
        labels[:] = 0.5
    return PreferenceDataset(obs, acts, returns, pairs, labels)


def _ensemble(seed: int = 0, cfg: RewardConfig = CFG) -> RewardEnsemble:
    return RewardEnsemble(OBS_DIM, ACT_DIM, cfg, np.random.default_rng(seed))


def test_learns_a_hand_made_reward():
    """True reward = first obs coordinate; 200 pairs labelled by the true return."""
    data = make_dataset(200, seed=0)
    ens = _ensemble()
    report = fit(ens, data, CFG, np.random.default_rng(0), epochs=8)
    assert report.n_pairs == 200 and report.n_validation == 40
    assert report.validation_accuracy > 0.9
    assert report.accuracy > 0.9 and report.loss < 0.3
    obs, acts, truth = fragments(300, np.random.default_rng(123))  # fresh fragments
    predicted = ens.returns(obs, acts).mean(axis=1)
    assert np.corrcoef(predicted, truth)[0, 1] > 0.9


@pytest.mark.parametrize("n_pairs", [1, 2, 9])
def test_tiny_datasets_train_without_a_split(n_pairs: int):
    ens = _ensemble()
    report = fit(ens, make_dataset(n_pairs), CFG, np.random.default_rng(0), epochs=3)
    assert report.n_pairs == n_pairs and report.n_validation == 0
    assert math.isnan(report.validation_accuracy) and math.isnan(report.validation_loss)
    assert math.isfinite(report.loss) and 0.0 <= report.accuracy <= 1.0
    assert report.steps == 3 * math.ceil(n_pairs / CFG.batch_size)
    assert report.l2_weight == CFG.initial_l2  # nothing to adapt it to
    assert np.isfinite(ens.returns(*fragments(3, np.random.default_rng(1))[:2])).all()


@pytest.mark.parametrize("n_pairs", [1, 12])
def test_all_ties_train_and_have_no_accuracy(n_pairs: int):
    data = make_dataset(n_pairs, tie=True)
    report = fit(_ensemble(), data, CFG, np.random.default_rng(0), epochs=5)
    assert math.isnan(report.accuracy) and math.isnan(report.validation_accuracy)
    assert math.isfinite(report.loss)
    assert (n_pairs >= CFG.min_pairs_for_validation) == math.isfinite(report.validation_loss)


def test_ties_pull_returns_together():
    data = make_dataset(1, tie=True)
    ens = _ensemble()
    a, b = data.pairs[0]
    gap_before = np.abs(np.diff(ens.returns(data.obs[[a, b]], data.acts[[a, b]]), axis=0))
    fit(ens, data, CFG, np.random.default_rng(0), epochs=50)
    gap_after = np.abs(np.diff(ens.returns(data.obs[[a, b]], data.acts[[a, b]]), axis=0))
    assert (gap_after < gap_before).all()


def test_empty_dataset_reports_nan():
    data = PreferenceDataset.empty(5, OBS_DIM, ACT_DIM)
    report = fit(_ensemble(), data, CFG, np.random.default_rng(0), epochs=3)
    assert report.n_pairs == 0 and report.steps == 0 and math.isnan(report.loss)


def test_same_seeds_give_identical_weights_and_other_seeds_do_not():
    data = make_dataset(30)
    probe = fragments(5, np.random.default_rng(7))[:2]

    def trained(init_seed: int, fit_seed: int) -> np.ndarray:
        ens = _ensemble(init_seed)
        fit(ens, data, CFG, np.random.default_rng(fit_seed), epochs=3)
        return ens.returns(*probe)

    first = trained(0, 0)
    np.testing.assert_array_equal(first, trained(0, 0))
    assert not np.allclose(first, trained(0, 1))  # other resamples and order
    assert not np.allclose(first, trained(1, 0))  # other initial weights


def test_bootstrap_makes_members_differ():
    """Members that start identical and see every pair in one batch stay close without
    bootstrap (Adam's sign-like first steps amplify the summation order a little) and part
    ways with it."""
    data = make_dataset(12)

    def member_spread(bootstrap: bool) -> float:
        cfg = RewardConfig(
            batch_size=100,
            bootstrap=bootstrap,
            min_pairs_for_validation=100,
            action_term="joint",  # one StackedMLP, whose layers are set equal below
        )
        ens = _ensemble(cfg=cfg)
        for weight, bias in ens.net.mlp._layers:
            weight.data[:] = weight.data[0]
            bias.data[:] = bias.data[0]
        fit(ens, data, cfg, np.random.default_rng(0), epochs=10)
        return float(ens.returns(data.obs, data.acts).std(axis=1).max())

    assert member_spread(bootstrap=True) > 20 * member_spread(bootstrap=False)


def test_l2_weight_grows_when_validation_loss_runs_away():
    data = make_dataset(60)
    data.labels = np.random.default_rng(0).integers(0, 2, size=60).astype(np.float32)
    report = fit(_ensemble(), data, CFG, np.random.default_rng(0), epochs=20)
    assert report.validation_loss > CFG.l2_bounds[1] * report.loss
    assert report.l2_weight > CFG.initial_l2


def test_normaliser_is_set_from_the_dataset():
    data = make_dataset(5)
    ens = _ensemble()
    fit(ens, data, CFG, np.random.default_rng(0), epochs=0)
    steps = np.concatenate([data.obs, data.acts], axis=-1).reshape(-1, OBS_DIM + ACT_DIM)
    mean, var = ens.net.norm.mean.numpy(), ens.net.norm.var.numpy()
    np.testing.assert_allclose(mean[:OBS_DIM], steps[:, :OBS_DIM].mean(axis=0), rtol=1e-5)
    # the control cost's actions (the default action term) are scaled, not centred
    np.testing.assert_allclose(mean[OBS_DIM:], 0.0)
    second_moment = (steps[:, OBS_DIM:] ** 2).mean(axis=0)
    np.testing.assert_allclose(var[OBS_DIM:], second_moment, rtol=1e-5)
    fit(ens, data, CFG, np.random.default_rng(0), epochs=0)  # refit, not counted twice
    assert float(ens.net.norm.count) == steps.shape[0]


def test_validation_split_is_stable_as_the_dataset_grows():
    assert not validation_mask(CFG.min_pairs_for_validation - 1, CFG).any()
    small, large = validation_mask(50, CFG), validation_mask(500, CFG)
    np.testing.assert_array_equal(large[:50], small)
    assert abs(large.mean() - CFG.validation_fraction) < 0.02


def test_mismatched_inputs_raise():
    data = make_dataset(3)
    with pytest.raises(ValueError, match="dims"):
        fit(
            RewardEnsemble(OBS_DIM + 1, ACT_DIM, CFG, np.random.default_rng(0)),
            data,
            CFG,
            np.random.default_rng(0),
            epochs=1,
        )
    with pytest.raises(ValueError, match="epochs"):
        fit(_ensemble(), data, CFG, np.random.default_rng(0), epochs=-1)
    data.labels[0] = 2.0
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        fit(_ensemble(), data, CFG, np.random.default_rng(0), epochs=1)


@pytest.mark.parametrize("term", ["additive", "cost"])
def test_separate_action_terms_learn_a_state_reward_and_a_control_cost(term):
    """True reward = obs[0] − acts[0]²: separable, as the SPEC envs' rewards are."""
    obs, acts, _ = fragments(400, np.random.default_rng(0))
    returns = (obs[..., 0] - acts[..., 0] ** 2).sum(axis=1).astype(np.float64)
    pairs = np.arange(400).reshape(200, 2)
    labels = (returns[pairs[:, 0]] > returns[pairs[:, 1]]).astype(np.float32)
    cfg = RewardConfig(action_term=term)
    ens = _ensemble(cfg=cfg)
    assert type(ens.net.mlp).__name__ == "AdditiveMLP"
    fit(ens, PreferenceDataset(obs, acts, returns, pairs, labels), cfg, np.random.default_rng(0), 8)
    test_obs, test_acts, _ = fragments(300, np.random.default_rng(123))
    truth = (test_obs[..., 0] - test_acts[..., 0] ** 2).sum(axis=1)
    assert np.corrcoef(ens.returns(test_obs, test_acts).mean(axis=1), truth)[0, 1] > 0.9
    zero, full = np.zeros((1, ACT_DIM)), np.array([[1.0, 0.0]])
    state = test_obs[:1, 0]
    assert ens.mean_reward(state, full)[0] < ens.mean_reward(state, zero)[0]  # a cost
    # a fresh fit from scratch (warm_start off) rebuilds the same kind of members
    ens.reinitialise(np.random.default_rng(1))
    assert type(ens.net.mlp).__name__ == "AdditiveMLP"
