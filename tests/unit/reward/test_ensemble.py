import pickle
from pathlib import Path

import cloudpickle
import numpy as np
import pytest
import torch

from groupwise.config import RewardConfig
from groupwise.reward import RewardEnsemble

OBS, ACT = 5, 2


def _ensemble(seed: int = 0, cfg: RewardConfig | None = None) -> RewardEnsemble:
    return RewardEnsemble(OBS, ACT, cfg or RewardConfig(), np.random.default_rng(seed))


def _inputs(*batch: int, seed: int = 1) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return rng.normal(size=(*batch, OBS)), rng.normal(size=(*batch, ACT))


def test_prediction_shapes_and_consistency():
    ens = _ensemble(cfg=RewardConfig(ensemble_size=4))
    obs, acts = _inputs(6, 3)
    steps = ens.step_rewards(obs, acts)
    assert steps.shape == (4, 6, 3)
    returns = ens.returns(obs, acts)
    assert returns.shape == (6, 4)
    np.testing.assert_allclose(returns, steps.sum(axis=-1).T, rtol=1e-5, atol=1e-6)
    flat_obs, flat_acts = obs.reshape(-1, OBS), acts.reshape(-1, ACT)
    mean = ens.mean_reward(flat_obs, flat_acts)
    assert mean.shape == (18,) and mean.dtype == np.float32
    np.testing.assert_allclose(mean, steps.reshape(4, -1).mean(axis=0), rtol=1e-5, atol=1e-6)
    assert ens.step_rewards(*_inputs(0)).shape == (4, 0)


def test_members_differ_and_construction_is_seeded():
    obs, acts = _inputs(7)
    rewards = _ensemble(seed=3).step_rewards(obs, acts)
    assert not np.allclose(rewards[0], rewards[1])
    np.testing.assert_array_equal(rewards, _ensemble(seed=3).step_rewards(obs, acts))
    assert not np.allclose(rewards, _ensemble(seed=4).step_rewards(obs, acts))


def test_construction_leaves_the_global_torch_rng_alone():
    state = torch.get_rng_state()
    _ensemble()
    assert torch.equal(state, torch.get_rng_state())


def test_bad_shapes_raise():
    ens = _ensemble()
    obs, acts = _inputs(3)
    with pytest.raises(ValueError, match="expected obs"):
        ens.step_rewards(obs[:, :-1], acts)
    with pytest.raises(ValueError, match="batch shape"):
        ens.step_rewards(obs, acts[:2])
    with pytest.raises(ValueError, match="N, L, dim"):
        ens.returns(obs, acts)
    with pytest.raises(ValueError, match="expected obs"):
        ens.mean_reward(obs, acts[:, :1])


def test_predicting_never_moves_the_normaliser():
    ens = _ensemble()
    ens.update_normalizer(*_inputs(20, seed=2))
    before = {k: v.clone() for k, v in ens.net.state_dict().items()}
    obs, acts = _inputs(4, 3)
    ens.step_rewards(obs, acts)
    ens.returns(obs, acts)
    ens.mean_reward(obs[:, 0], acts[:, 0])
    for name, value in ens.net.state_dict().items():
        assert torch.equal(value, before[name]), name


def test_save_and_load_round_trip(tmp_path: Path):
    ens = _ensemble(5, RewardConfig(hidden_sizes=(8, 8)))
    ens.update_normalizer(*_inputs(30, seed=6))
    ens.l2_weight = 0.125
    path = tmp_path / "reward.pt"
    ens.save(path)
    assert isinstance(torch.load(path, weights_only=True), dict)

    obs, acts = _inputs(4, 3)
    rebuilt = RewardEnsemble.load(path)
    assert rebuilt.cfg == ens.cfg and rebuilt.l2_weight == 0.125
    np.testing.assert_array_equal(rebuilt.returns(obs, acts), ens.returns(obs, acts))

    other = _ensemble(9, RewardConfig(hidden_sizes=(8, 8)))
    predict = other.mean_reward  # a bound method held elsewhere (PPO) sees the loaded weights
    other.load_state(path)
    np.testing.assert_array_equal(
        predict(obs[:, 0], acts[:, 0]), ens.mean_reward(obs[:, 0], acts[:, 0])
    )


def test_load_state_refuses_another_shape(tmp_path: Path):
    path = tmp_path / "reward.pt"
    _ensemble(cfg=RewardConfig(hidden_sizes=(8,))).save(path)
    with pytest.raises(ValueError, match="does not fit"):
        _ensemble(cfg=RewardConfig(hidden_sizes=(9,))).load_state(path)
    with pytest.raises(ValueError, match="obs"):
        RewardEnsemble(
            OBS + 1, ACT, RewardConfig(hidden_sizes=(8,)), np.random.default_rng(0)
        ).load_state(path)


@pytest.mark.parametrize("dumps", [pickle.dumps, cloudpickle.dumps])
def test_ensemble_and_its_mean_reward_pickle(dumps):
    ens = _ensemble()
    obs, acts = _inputs(8)
    copy = pickle.loads(dumps(ens))
    np.testing.assert_array_equal(copy.mean_reward(obs, acts), ens.mean_reward(obs, acts))
    reward_fn = pickle.loads(dumps(ens.mean_reward))
    np.testing.assert_array_equal(reward_fn(obs, acts), ens.mean_reward(obs, acts))


def test_standardised_output_is_what_ppo_sees_and_survives_save(tmp_path: Path):
    ens = _ensemble(cfg=RewardConfig(ensemble_size=3))
    obs, acts = _inputs(200, seed=3)
    raw = ens.step_rewards(obs, acts)
    ens.standardise_output(obs, acts)
    standard = (raw - raw.mean(axis=1, keepdims=True)) / raw.std(axis=1, keepdims=True)
    np.testing.assert_allclose(ens.mean_reward(obs, acts), standard.mean(axis=0), atol=1e-4)
    np.testing.assert_array_equal(ens.step_rewards(obs, acts), raw)  # training's view unchanged
    ens.save(tmp_path / "r.pt")
    again = RewardEnsemble.load(tmp_path / "r.pt")
    np.testing.assert_allclose(again.mean_reward(obs, acts), ens.mean_reward(obs, acts))


def test_reinitialise_draws_fresh_seeded_weights():
    a, b = _ensemble(), _ensemble()
    obs, acts = _inputs(9)
    before = a.step_rewards(obs, acts)
    a.reinitialise(np.random.default_rng(5))
    b.reinitialise(np.random.default_rng(5))
    assert not np.allclose(a.step_rewards(obs, acts), before)
    np.testing.assert_array_equal(a.step_rewards(obs, acts), b.step_rewards(obs, acts))


def test_observation_only_members_ignore_the_actions_but_check_them(tmp_path: Path):
    ens = _ensemble(3, RewardConfig(use_actions=False, hidden_sizes=(8, 8)))
    assert ens.in_dim == OBS
    obs, acts = _inputs(4, 3)
    other_acts = acts + 5.0
    np.testing.assert_array_equal(ens.returns(obs, acts), ens.returns(obs, other_acts))
    np.testing.assert_array_equal(
        ens.mean_reward(obs[:, 0], acts[:, 0]), ens.mean_reward(obs[:, 0], other_acts[:, 0])
    )
    with pytest.raises(ValueError):
        ens.mean_reward(obs[:, 0], acts[:, 0, :1])
    ens.save(tmp_path / "reward.pt")
    rebuilt = RewardEnsemble.load(tmp_path / "reward.pt")
    assert not rebuilt.cfg.use_actions
    np.testing.assert_array_equal(rebuilt.returns(obs, acts), ens.returns(obs, acts))


def test_files_written_before_observation_only_members_load_with_actions(tmp_path: Path):
    ens = _ensemble(4, RewardConfig(use_actions=True, hidden_sizes=(8, 8)))
    assert ens.in_dim == OBS + ACT
    path = tmp_path / "reward.pt"
    ens.save(path)
    payload = torch.load(path, weights_only=True)
    del payload["config"]["use_actions"]  # as written before the field existed
    torch.save(payload, path)
    rebuilt = RewardEnsemble.load(path)
    assert rebuilt.cfg.use_actions
    obs, acts = _inputs(4, 3)
    np.testing.assert_array_equal(rebuilt.returns(obs, acts), ens.returns(obs, acts))


def test_additive_ensemble_saves_and_loads(tmp_path: Path):
    ens = _ensemble(2, RewardConfig(action_term="additive", hidden_sizes=(8, 8)))
    ens.save(tmp_path / "reward.pt")
    rebuilt = RewardEnsemble.load(tmp_path / "reward.pt")
    assert rebuilt.cfg.action_term == "additive"
    obs, acts = _inputs(5)
    np.testing.assert_allclose(rebuilt.mean_reward(obs, acts), ens.mean_reward(obs, acts))
    # without action inputs there is nothing to add: one MLP over the observation
    alone = _ensemble(2, RewardConfig(action_term="additive", use_actions=False))
    assert alone.net.mlp.in_dim == OBS
