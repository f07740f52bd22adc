"""Agreement between annotators and with a reward model: hand-checkable numbers."""

import numpy as np
import pytest

from groupwise.preferences.agreement import (
    Agreement,
    ModelAgreement,
    cohen_kappa,
    model_agreement,
    oriented,
    rater_agreement,
)


def test_kappa_of_a_hand_computed_three_label_example():
    first = [1, 1, 1, 1, 0, 0, 0, 0.5, 0.5, 1]
    second = [1, 1, 1, 0, 0, 0, 1, 0.5, 0, 1]
    # p_o = 7/10; label frequencies: first 1: .5, 0: .3, ½: .2; second 1: .5, 0: .4, ½: .1
    # p_e = .5·.5 + .3·.4 + .2·.1 = .39;  κ = (.7 − .39) / (1 − .39) = .31 / .61
    assert cohen_kappa(first, second) == pytest.approx(0.31 / 0.61)


def test_kappa_of_two_labels_equals_the_closed_form_of_the_two_by_two_table():
    rng = np.random.default_rng(0)
    for _ in range(20):
        first = rng.integers(0, 2, size=30).astype(float)
        flips = rng.random(30) < 0.3
        second = np.where(flips, 1 - first, first)
        a = int(np.sum((first == 1) & (second == 1)))
        b = int(np.sum((first == 1) & (second == 0)))
        c = int(np.sum((first == 0) & (second == 1)))
        d = int(np.sum((first == 0) & (second == 0)))
        closed = 2 * (a * d - b * c) / ((a + b) * (b + d) + (a + c) * (c + d))
        assert cohen_kappa(list(first), list(second)) == pytest.approx(closed)


def test_kappa_is_one_for_perfect_agreement_and_undefined_without_chance_variation():
    assert cohen_kappa([1, 0, 0.5], [1, 0, 0.5]) == pytest.approx(1.0)
    assert cohen_kappa([1, 0], [0, 1]) == pytest.approx(-1.0)
    assert cohen_kappa([], []) is None
    assert cohen_kappa([1, 1, 1], [1, 1, 1]) is None  # p_e = 1: 0 / 0
    with pytest.raises(ValueError, match="same items"):
        cohen_kappa([1], [1, 0])


def test_oriented_puts_the_pair_in_sorted_order():
    assert oriented("b7", "b3", 1.0) == (("b3", "b7"), 0.0)
    assert oriented("b3", "b7", 1.0) == (("b3", "b7"), 1.0)
    assert oriented("b7", "b3", 0.5) == (("b3", "b7"), 0.5)


def test_rater_agreement_pools_the_pairs_shared_with_each_other_annotator():
    mine = {"p": 1.0, "q": 0.0, "r": 0.5}
    bob = {"p": 1.0, "q": 1.0, "s": 0.0}  # shares p (alike), q (not)
    eve = {"r": 0.5, "x": 1.0}  # shares r (alike)
    found = rater_agreement(mine, [bob, eve])
    assert found.n == 3 and found.share == pytest.approx(2 / 3)
    # mine: 1, 0, ½ against 1, 1, ½: p_o = 2/3, p_e = ⅓·⅔ + ⅓·0 + ⅓·⅓ = 1/3; κ = ½
    assert found.kappa == pytest.approx(0.5)
    assert rater_agreement(mine, [{"z": 1.0}]) == Agreement(kappa=None, share=None, n=0)
    assert rater_agreement(mine, []) == Agreement(kappa=None, share=None, n=0)


def test_model_agreement_counts_strict_preferences_with_a_margin():
    labels = {"p": 1.0, "q": 0.0, "r": 0.5, "s": 1.0, "t": 1.0}
    margins = {"p": 2.0, "q": 0.5, "r": 1.0, "s": 0.0}  # t: no prediction
    # p agrees, q disagrees (model prefers a, person b); r equal, s no margin, t unknown
    assert model_agreement(labels, margins) == ModelAgreement(share=0.5, n=2)
    assert model_agreement({}, margins) == ModelAgreement(share=None, n=0)
