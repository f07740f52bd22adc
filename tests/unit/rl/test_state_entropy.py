"""The k-nearest-neighbour state-entropy bonus (PEBBLE) and its PPO reward."""

import numpy as np
import pytest

from groupwise.rl.state_entropy import (
    StateEntropyReward,
    entropy_bonus,
    knn_distance,
    standardised,
)


def test_knn_distance_on_a_line_is_hand_checkable():
    line = np.arange(6.0)[:, None]  # 0, 1, …, 5
    # from 0 the neighbours are 1, 2, 3, …: the 2nd is 2 away
    assert knn_distance(np.array([[0.0]]), line, k=2, exclude_self=True)[0] == 2.0
    # a state not among the reference: its 1st neighbour is the nearest point
    assert knn_distance(np.array([[2.4]]), line, k=1)[0] == pytest.approx(0.4)


def test_the_bonus_rises_for_more_spread_out_states():
    rng = np.random.default_rng(0)
    base = rng.standard_normal((500, 4))
    anchor = rng.standard_normal((500, 4))  # the common reference scale
    reference = np.vstack([anchor, base * 0.1, base])
    narrow = entropy_bonus(base * 0.1, reference, k=5)
    wide = entropy_bonus(base, reference, k=5)
    assert wide.mean() > narrow.mean() + 0.3
    # a batch against itself: log(1 + d_k) grows with the spread
    means = [entropy_bonus(base * s, base * s, exclude_self=True).mean() for s in (0.1, 1, 10)]
    assert means == sorted(means)


def test_the_bonus_of_an_isolated_state_is_higher_than_of_a_crowded_one():
    crowd = np.zeros((20, 2)) + np.linspace(0, 0.1, 20)[:, None]
    states = np.vstack([crowd, [[5.0, 5.0]]])
    bonus = entropy_bonus(states, states, k=5, exclude_self=True)
    assert bonus.argmax() == 20


def test_standardising_divides_by_the_reference_sd():
    reference = np.array([[0.0, 0.0], [2.0, 20.0]])
    scaled, ref = standardised(np.array([[1.0, 10.0]]), reference)
    np.testing.assert_allclose(scaled, [[1.0, 1.0]])
    np.testing.assert_allclose(ref.std(axis=0), [1.0, 1.0])


def test_too_few_reference_states_fail():
    with pytest.raises(ValueError, match="at least 6"):
        knn_distance(np.zeros((1, 2)), np.zeros((5, 2)), k=5, exclude_self=True)


def _feed(reward: StateEntropyReward, states: np.ndarray, batch: int = 8) -> np.ndarray:
    return np.concatenate(
        [reward(states[i : i + batch], np.zeros((batch, 1))) for i in range(0, len(states), batch)]
    )


def test_the_reward_pays_more_for_states_away_from_recent_ones():
    rng = np.random.default_rng(1)
    reward = StateEntropyReward(k=5, capacity=400, rebuild_every=64)
    _feed(reward, rng.standard_normal((400, 3)) * 0.1)  # a crowded past
    near = reward(rng.standard_normal((8, 3)) * 0.1, np.zeros((8, 1)))
    far = reward(rng.standard_normal((8, 3)) * 0.1 + 3.0, np.zeros((8, 1)))
    assert far.min() > near.max()
    assert near.dtype == np.float32 and near.shape == (8,)


def test_the_reward_is_zero_until_k_states_were_seen_and_repeats_exactly():
    rng = np.random.default_rng(2)
    states = rng.standard_normal((200, 3))
    first, second = StateEntropyReward(k=5, rebuild_every=32), StateEntropyReward(rebuild_every=32)
    paid = _feed(first, states, batch=4)
    assert not paid[:8].any()  # two batches of 4 before there are k = 5 states to compare with
    assert paid[8:].all()
    np.testing.assert_array_equal(paid, _feed(second, states, batch=4))
    assert len(first.bonus_means) == (200 - 8) // 32  # one mean per 32 states paid
