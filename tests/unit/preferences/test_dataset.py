import numpy as np

from groupwise.episodes.fragments import Fragment
from groupwise.preferences.dataset import PreferenceDataset, wrong_labels
from groupwise.preferences.pairs import Pair


def _fragment(ret: float, episode: int) -> Fragment:
    return Fragment(
        obs=np.full((2, 3), ret, dtype=np.float32),
        acts=np.zeros((2, 1), dtype=np.float32),
        true_rewards=np.array([ret, 0.0]),
        episode=episode,
        start=0,
        reset_seed=0,
    )


def test_add_stores_each_used_fragment_once_and_round_trips(tmp_path):
    pool = [_fragment(r, i) for i, r in enumerate([1.0, 2.0, 3.0, 4.0])]
    data = PreferenceDataset.empty(length=2, obs_dim=3, act_dim=1)
    data.add(pool, [Pair(0, 1, 0.0), Pair(0, 2, 1.0)], round_index=0)
    data.add(pool, [Pair(3, 2, 0.5)], round_index=1)
    assert len(data) == 3 and data.n_fragments == 5  # 0, 1, 2 then 2, 3 again
    np.testing.assert_array_equal(data.rounds, [0, 0, 1])
    # pair rows point at the right fragments
    np.testing.assert_array_equal(data.true_returns[data.pairs[:, 0]], [1.0, 1.0, 4.0])
    # labels: 1 < 2 so 0.0 is right; 1 < 3 so 1.0 is wrong; 4 != 3 so 0.5 is wrong
    assert data.label_error_rate() == 2 / 3

    data.save(tmp_path / "d.npz")
    loaded = PreferenceDataset.load(tmp_path / "d.npz")
    for name in ("obs", "acts", "true_returns", "pairs", "labels", "rounds"):
        np.testing.assert_array_equal(getattr(loaded, name), getattr(data, name))


def test_empty_dataset_has_nan_error_rate():
    assert np.isnan(PreferenceDataset.empty(2, 3, 1).label_error_rate())
    assert np.isnan(PreferenceDataset.empty(2, 3, 1).label_error_rate(untied=True))


def test_untied_error_rate_leaves_out_pairs_of_equal_return():
    pool = [_fragment(r, i) for i, r in enumerate([0.0, 0.0, 1.0])]
    data = PreferenceDataset.empty(length=2, obs_dim=3, act_dim=1)
    # a tie labelled 1.0 (arbitrary), a right label, a wrong label
    data.add(pool, [Pair(0, 1, 1.0), Pair(2, 0, 1.0), Pair(1, 2, 1.0)], round_index=0)
    np.testing.assert_array_equal(data.tied(), [True, False, False])
    assert data.label_error_rate() == 2 / 3
    assert data.label_error_rate(untied=True) == 1 / 2
    only_tie = np.array([True, False, False])
    assert np.isnan(data.label_error_rate(only_tie, untied=True))


def test_wrong_labels_by_hand():
    wrong = wrong_labels(
        np.array([2.0, 1.0, 1.0, 5.0]),
        np.array([1.0, 2.0, 1.0, 1.0]),
        np.array([1.0, 1.0, 0.5, 0.5]),
    )
    np.testing.assert_array_equal(wrong, [False, True, False, True])
