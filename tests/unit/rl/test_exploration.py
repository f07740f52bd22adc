import numpy as np

from groupwise.rl.rollout import exploration_mask


def test_exploration_share_matches_the_fraction_and_comes_in_stretches():
    mask = exploration_mask(200, 1000, 0.25, np.random.default_rng(0))
    assert abs(mask.mean() - 0.25) < 0.02
    switches = np.count_nonzero(mask[:, 1:] != mask[:, :-1])
    random_steps = mask.sum()
    assert random_steps / (switches / 2) > 5  # stretches, not isolated steps


def test_no_exploration():
    assert not exploration_mask(3, 10, 0.0, np.random.default_rng(0)).any()
