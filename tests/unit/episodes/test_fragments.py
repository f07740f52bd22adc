import dataclasses

import numpy as np
import pytest

from groupwise.episodes.fragments import Trajectory, most_uncertain, stack_fragments, tile_fragments


def _trajectory(length: int, episode: int = 0) -> Trajectory:
    steps = np.arange(length, dtype=np.float32)
    return Trajectory(
        obs=np.stack([steps, -steps], axis=1),
        acts=steps[:, None] * 10,
        actions=steps[:, None] * 10,
        true_rewards=steps.astype(np.float64),
        reset_seed=7,
        episode=episode,
    )


def test_tiling_gives_non_overlapping_windows_and_drops_the_remainder():
    fragments = tile_fragments([_trajectory(10), _trajectory(7, episode=1)], length=3)
    assert [(f.episode, f.start) for f in fragments] == [(0, 0), (0, 3), (0, 6), (1, 0), (1, 3)]
    assert all(f.length == 3 for f in fragments)
    # the window's observations, actions and rewards all come from the same steps
    second = fragments[1]
    np.testing.assert_array_equal(second.obs[:, 0], [3, 4, 5])
    np.testing.assert_array_equal(second.acts[:, 0], [30, 40, 50])
    assert second.true_return == 3 + 4 + 5
    assert len({f.key for f in fragments}) == len(fragments)


def test_windows_never_cross_the_end_of_an_episode():
    lengths = [2, 9, 3, 13, 5]  # episodes of their own lengths, as terminating envs give
    episodes = [
        dataclasses.replace(t, obs=t.obs + 100 * t.episode)  # 100 × episode + step
        for t in (_trajectory(n, episode=i) for i, n in enumerate(lengths))
    ]
    fragments = tile_fragments(episodes, length=3)
    assert [sum(f.episode == i for f in fragments) for i in range(5)] == [0, 3, 1, 4, 1]
    for f in fragments:
        assert f.start + f.length <= lengths[f.episode]
        np.testing.assert_array_equal(f.obs[:, 0], 100 * f.episode + f.start + np.arange(3))


def test_stack_shapes():
    obs, acts = stack_fragments(tile_fragments([_trajectory(9)], length=3))
    assert obs.shape == (3, 3, 2) and acts.shape == (3, 3, 1)


def test_trajectory_rejects_mismatched_lengths():
    with pytest.raises(ValueError, match="disagree"):
        Trajectory(np.zeros((3, 2)), np.zeros((2, 1)), np.zeros((3, 1)), np.zeros(3), 0, 0)


def test_most_uncertain_keeps_highest_scores_in_pool_order():
    np.testing.assert_array_equal(most_uncertain(np.array([0.1, 5.0, 0.3, 4.0]), 2), [1, 3])
    np.testing.assert_array_equal(most_uncertain(np.array([1.0, 2.0]), 5), [0, 1])
