"""The five-frame strip: where the best moment is, which frames show it, how they are laid out."""

import numpy as np
import pytest

from groupwise.envs import TARGET_SCORE_KEY, TARGETS, make_env
from groupwise.study.case_studies.film import best_moment, film_episode, strip_image, strip_steps


def test_best_moment_is_the_window_with_the_highest_sum() -> None:
    scores = np.array([0.0, 1.0, 0.0, 5.0, 5.0, 0.0, 4.0, 4.0, 4.0])
    assert best_moment(scores, 2) == 3  # 5 + 5
    assert best_moment(scores, 3) == 6  # 4 + 4 + 4 beats 5 + 5 + 0
    assert best_moment(scores, 1) == 3  # the earliest of equal windows
    assert best_moment(scores, 50) == 0  # longer than the episode: all of it


def test_strip_spans_the_targets_moment_from_its_best_start() -> None:
    target = TARGETS["hopper-backflip"]  # moment 1 s = 125 steps of 0.008 s
    scores = np.zeros(1000)
    scores[400:525] = 1.0
    steps = strip_steps(scores, target, 0.008)
    assert steps.tolist() == [400, 431, 462, 494, 525]  # states, first to last of the moment
    short = strip_steps(np.ones(10), target, 0.008)
    assert short.tolist() == [0, 2, 5, 8, 10]


def test_strip_image_puts_frames_side_by_side_with_white_gaps() -> None:
    frames = np.stack([np.full((4, 6, 3), i * 40, dtype=np.uint8) for i in range(5)])
    image = strip_image(frames, gap=2)
    assert image.shape == (4, 5 * 6 + 4 * 2, 3)
    assert (image[:, 0:6] == 0).all() and (image[:, 6:8] == 255).all()
    assert (image[:, 8:14] == 40).all() and (image[:, -6:] == 160).all()


def test_strip_of_real_frames_matches_the_episode_scores() -> None:
    env = make_env("Hopper-backflip")
    env.reset(seed=4)
    rng = np.random.default_rng(4)
    actions = rng.uniform(-1, 1, size=(200, 3)).astype(np.float32)
    scores = np.array([env.step(a)[4][TARGET_SCORE_KEY] for a in actions])
    film = film_episode(TARGETS["hopper-backflip"], actions, 4, scores, size=(64, 48))
    assert film.frames.shape == (51, 48, 64, 3)  # states 0, 4, …, 200
    assert film.strip.shape == (5, 48, 64, 3) and film.fps == pytest.approx(31.25)
    with pytest.raises(ValueError, match="did not reproduce"):
        film_episode(TARGETS["hopper-backflip"], actions, 5, scores, size=(64, 48))
