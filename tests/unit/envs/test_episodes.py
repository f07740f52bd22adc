"""`check_episode_length`: whether a random policy's episodes of an env can hold one
behaviour, before a session of it is created (issue 23)."""

import numpy as np
import pytest

from groupwise.envs.episodes import GIVE_UP_EPISODES, check_episode_length


def test_episodes_that_end_before_one_window_are_refused_with_their_lengths():
    with pytest.raises(ValueError) as refused:
        check_episode_length(
            "InvertedPendulum-v5", 25, np.random.default_rng(0), " (clip_seconds = 1 s)"
        )
    message = str(refused.value)
    assert message.startswith(f"a random policy's {GIVE_UP_EPISODES} episodes of ")
    assert "none long enough for one window of 25 steps (clip_seconds = 1 s)" in message


@pytest.mark.parametrize(
    ("env", "length"),
    [
        ("InvertedPendulum-v5", 2),  # the pole takes at least 3 steps to tip
        ("Pendulum-v1", 25),  # never terminates
        ("GridWorld", 10_000),  # a groupwise env never ends early: not played at all
    ],
)
def test_episodes_long_enough_pass(env, length):
    check_episode_length(env, length, np.random.default_rng(0))


def test_an_unknown_env_is_a_value_error():
    with pytest.raises(ValueError, match="Bogus-v9"):
        check_episode_length("Bogus-v9", 5, np.random.default_rng(0))
