"""Study behaviours: biased random policies, round-robin trajectories, random windows."""

import gymnasium as gym
import numpy as np

from groupwise.study.clustering.policy_mix import BiasedRandomPolicy, biased_policies, sample_mixed


def test_box_bias_shifts_the_action_mean_within_bounds() -> None:
    space = gym.spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
    policy = BiasedRandomPolicy(space, offset=np.array([0.5, -0.5]))
    actions = policy.act(np.zeros((4000, 3), dtype=np.float32), np.random.default_rng(0))
    assert actions.shape == (4000, 2) and actions.dtype == np.float32
    assert actions.min() >= -1 and actions.max() <= 1
    assert actions[:, 0].mean() > 0.3 and actions[:, 1].mean() < -0.3


def test_discrete_bias_follows_the_probabilities() -> None:
    space = gym.spaces.Discrete(3)
    policy = BiasedRandomPolicy(space, probabilities=np.array([0.8, 0.2, 0.0]))
    actions = policy.act(np.zeros((2000, 1), dtype=np.float32), np.random.default_rng(0))
    assert set(np.unique(actions)) <= {0, 1}
    assert 0.75 < (actions == 0).mean() < 0.85


def test_biased_policies_are_seeded() -> None:
    space = gym.spaces.Box(-1.0, 1.0, shape=(3,), dtype=np.float32)
    a = biased_policies(space, 3, 0.5, np.random.default_rng(1))
    b = biased_policies(space, 3, 0.5, np.random.default_rng(1))
    assert [name for name, _ in a] == ["biased-0", "biased-1", "biased-2"]
    for (_, p), (_, q) in zip(a, b, strict=True):
        assert isinstance(p, BiasedRandomPolicy) and isinstance(q, BiasedRandomPolicy)
        np.testing.assert_array_equal(p.offset, q.offset)


def test_sample_mixed_deals_trajectories_round_robin() -> None:
    space = gym.spaces.Discrete(5)
    policies = [
        ("stay", BiasedRandomPolicy(space, probabilities=np.eye(5)[0])),
        ("right", BiasedRandomPolicy(space, probabilities=np.eye(5)[1])),
    ]
    fragments, sources = sample_mixed("GridWorld", policies, 5, 2, 30, np.random.default_rng(0))
    assert len(fragments) == 10
    assert [f.episode for f in fragments] == [0, 0, 1, 1, 2, 2, 3, 3, 4, 4]
    assert sources == ["stay", "stay", "right", "right"] * 2 + ["stay", "stay"]
    for fragment, source in zip(fragments, sources, strict=True):
        steps = np.diff(fragment.obs[:, :2], axis=0)
        assert (steps[:, 1] == 0).all()  # neither policy moves along y
        if source == "stay":
            assert (steps == 0).all()
        else:  # +x until the wall
            assert (steps[:, 0] >= 0).all()
        assert fragment.start % 30 == 0
