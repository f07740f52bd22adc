import copy
import pickle

import numpy as np
import pytest
import torch

from groupwise.reward.network import AdditiveMLP, RunningNorm, StackedMLP


def test_running_norm_merges_batches_like_one_pass():
    rng = np.random.default_rng(0)
    parts = [rng.normal(loc=3.0, scale=2.0, size=(n, 3)) for n in (5, 1, 40)]
    norm = RunningNorm(3)
    for part in parts:
        norm.update(part)
    everything = np.concatenate(parts)
    np.testing.assert_allclose(norm.mean.numpy(), everything.mean(axis=0), rtol=1e-5)
    np.testing.assert_allclose(norm.var.numpy(), everything.var(axis=0), rtol=1e-5)
    assert float(norm.count) == 46


def test_running_norm_is_identity_until_updated_and_forward_does_not_update():
    norm = RunningNorm(2)
    x = torch.tensor([[1.0, -2.0], [3.0, 4.0]])
    torch.testing.assert_close(norm(x), x)
    norm.update(np.array([[0.0, 0.0], [2.0, 4.0]]))  # mean (1, 2), var (1, 4)
    before = norm.state_dict()
    torch.testing.assert_close(norm(x), torch.tensor([[0.0, -2.0], [2.0, 1.0]]))
    for name, value in norm.state_dict().items():
        torch.testing.assert_close(value, before[name])


def test_running_norm_clips_constant_features_and_resets():
    norm = RunningNorm(1, clip=5.0)
    norm.update(np.ones((4, 1)))
    assert norm(torch.tensor([[2.0]])).item() == 5.0
    norm.reset()
    assert norm(torch.tensor([[2.0]])).item() == 2.0


def test_running_norm_rejects_the_wrong_width():
    with pytest.raises(ValueError, match="expected 3 features"):
        RunningNorm(3).update(np.zeros((2, 4)))


def test_stacked_members_equal_plain_mlps():
    mlp = StackedMLP(3, 5, (7, 6), generator=torch.Generator().manual_seed(1))
    x = torch.randn(11, 5, generator=torch.Generator().manual_seed(2))
    out = mlp(x)
    assert out.shape == (3, 11)
    for k in range(3):
        torch.testing.assert_close(out[k], mlp.member(k)(x).squeeze(-1))
    # one batch per member gives the same as the shared batch repeated
    torch.testing.assert_close(mlp(x.expand(3, 11, 5).contiguous()), out)


def test_initialisation_comes_from_the_generator():
    def weights(seed: int) -> torch.Tensor:
        mlp = StackedMLP(2, 3, (4,), generator=torch.Generator().manual_seed(seed))
        return torch.cat([p.flatten() for p in mlp.parameters()])

    torch.testing.assert_close(weights(5), weights(5))
    assert not torch.equal(weights(5), weights(6))


def test_l2_penalty_sums_each_members_squared_weights():
    mlp = StackedMLP(2, 1, (1,))
    with torch.no_grad():
        for weight, bias in zip(mlp.weights, mlp.biases, strict=True):
            weight.copy_(torch.tensor([1.0, 2.0]).reshape(2, 1, 1))
            bias.fill_(9.0)  # biases are not penalised
    torch.testing.assert_close(mlp.l2_penalty(), torch.tensor([2.0, 8.0]))


def test_unknown_activation_is_refused():
    with pytest.raises(KeyError, match="unknown activation"):
        StackedMLP(1, 2, (3,), activation="swish")


@pytest.mark.parametrize("clone", [copy.deepcopy, lambda m: pickle.loads(pickle.dumps(m))])
def test_copies_compute_with_their_own_parameters(clone):
    mlp = StackedMLP(2, 3, (4,))
    twin = clone(mlp)
    with torch.no_grad():
        for p in twin.parameters():
            p.zero_()
    x = torch.ones(5, 3)
    assert torch.equal(twin(x), torch.zeros(2, 5))
    assert not torch.equal(mlp(x), torch.zeros(2, 5))


def test_additive_members_are_a_sum_of_an_observation_term_and_an_action_term():
    mlp = AdditiveMLP(3, 5, 3, (7, 6), generator=torch.Generator().manual_seed(1))
    x = torch.randn(4, 5)
    out = mlp(x)
    assert out.shape == (3, 4)
    torch.testing.assert_close(out, mlp.first(x[:, :3]) + mlp.second(x[:, 3:]))
    # no interaction: the change an action makes is the same in every state
    a, b = torch.randn(1, 2), torch.randn(1, 2)
    states = torch.randn(6, 3)
    with_a = mlp(torch.cat([states, a.expand(6, 2)], dim=1))
    with_b = mlp(torch.cat([states, b.expand(6, 2)], dim=1))
    difference = with_a - with_b  # (K, 6)
    torch.testing.assert_close(difference, difference[:, :1].expand(3, 6))
    torch.testing.assert_close(mlp(x.expand(3, 4, 5)), out)  # per-member batches too
    torch.testing.assert_close(mlp.l2_penalty(), mlp.first.l2_penalty() + mlp.second.l2_penalty())
    with pytest.raises(ValueError, match="split"):
        AdditiveMLP(2, 3, 3, (4,))


def test_a_control_cost_is_zero_at_zero_and_grows_with_the_action_squared():
    mlp = AdditiveMLP(2, 4, 3, (5,), second="cost")
    states = torch.randn(3, 3)
    rewards = [mlp(torch.cat([states, torch.full((3, 1), a)], dim=1)) for a in (0.0, 1.0, 2.0)]
    torch.testing.assert_close(rewards[0], mlp.first(states))
    cost_1, cost_2 = rewards[0] - rewards[1], rewards[0] - rewards[2]
    assert (cost_1 > 0).all()
    torch.testing.assert_close(cost_2, 4 * cost_1)
    torch.testing.assert_close(mlp.l2_penalty(), mlp.first.l2_penalty())


def test_uncentred_features_are_scaled_by_their_root_mean_square():
    rng = np.random.default_rng(0)
    parts = [rng.normal(loc=[1.0, 2.0], scale=[1.0, 0.5], size=(n, 2)) for n in (30, 50)]
    norm = RunningNorm(2)
    for part in parts:  # merged after each update, as the ensemble does
        norm.update(part)
        norm.uncentre(1)
    everything = np.concatenate(parts)
    assert float(norm.mean[1]) == 0.0
    np.testing.assert_allclose(float(norm.var[1]), (everything[:, 1] ** 2).mean(), rtol=1e-5)
    np.testing.assert_allclose(float(norm.mean[0]), everything[:, 0].mean(), rtol=1e-5)
