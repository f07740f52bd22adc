"""The walker's posture shares: each condition of a held split counted per step."""

import math

import numpy as np
import pytest

from groupwise.study.case_studies.splits_posture import posture_shares


def test_each_condition_and_all_three_are_shares_of_the_steps():
    separation = np.radians([100.0, 100.0, 150.0, 30.0])
    tilt = np.radians([10.0, 70.0, 50.0, 0.0])
    feet = np.array([2, 2, 1, 2])
    shares = posture_shares(separation, tilt, feet)
    assert shares["steps"] == 4
    assert shares["split"] == 0.75 and shares["upright"] == 0.75
    assert (shares["feet_0"], shares["feet_1"], shares["feet_2"]) == (0.0, 0.25, 0.75)
    assert shares["all"] == 0.25  # only the first step holds all three
    assert shares["separation"] == pytest.approx(math.radians(100.0))
    assert shares["tilt"] == pytest.approx(math.radians(30.0))
    assert shares["breaks_tilt"] == 250.0  # held at step 0, broken at step 1: 1 in 4 steps
    assert shares["breaks_split"] == shares["breaks_feet"] == 0.0


def test_a_split_that_wobbles_about_a_condition_breaks_on_it():
    upright, leaning = math.radians(55.0), math.radians(62.0)
    tilt = np.array([upright, leaning, upright, upright, leaning, upright, upright, upright])
    feet = np.array([2, 2, 2, 1, 2, 2, 2, 2])
    shares = posture_shares(np.full(8, math.radians(120.0)), tilt, feet)
    assert shares["all"] == 5 / 8
    assert shares["breaks_tilt"] == shares["breaks_feet"] == 1000 / 8  # step 4: already broken
    assert shares["breaks_split"] == 0.0


def test_a_new_episode_is_no_break():
    held, standing = math.radians(120.0), math.radians(0.0)
    separation = np.array([held, held, standing, held])  # two episodes of two steps
    tilt, feet = np.zeros(4), np.full(4, 2)
    assert posture_shares(separation, tilt, feet)["breaks_split"] == 250.0
    assert posture_shares(separation, tilt, feet, [2, 2])["breaks_split"] == 0.0
    with pytest.raises(ValueError, match="episodes of 3 steps"):
        posture_shares(separation, tilt, feet, [2, 1])


def test_empty_or_uneven_steps_are_refused():
    with pytest.raises(ValueError, match="non-empty"):
        posture_shares(np.zeros(0), np.zeros(0), np.zeros(0))
    with pytest.raises(ValueError, match="non-empty"):
        posture_shares(np.zeros(2), np.zeros(3), np.zeros(2))
