"""A session's behaviours cover the env's clip duration unless it asks for another; a new
session stores its L in steps, and old sessions keep theirs."""

import pytest

from groupwise.storage import SessionSettings


@pytest.mark.parametrize(
    ("env", "steps", "seconds"),
    [("Hopper", 188, 1.5), ("HalfCheetah", 30, 1.5), ("Reacher", 50, 1.0), ("GridWorld", 30, 1.0)],
)
def test_a_new_session_stores_the_env_default_clip_in_steps(
    env: str, steps: int, seconds: float
) -> None:
    resolved = SessionSettings().for_env(env)
    assert (resolved.fragment_length, resolved.clip_seconds) == (steps, seconds)
    assert resolved.run_config(env).loop.fragment_length == steps
    assert resolved.for_env(env) == resolved  # resolving again changes nothing


def test_a_session_may_ask_for_seconds_or_steps() -> None:
    two = SessionSettings(clip_seconds=2.0).for_env("Hopper")
    assert (two.fragment_length, two.clip_timing("Hopper").frames) == (250, 63)
    steps = SessionSettings(fragment_length=30).for_env("Hopper")  # the study's L
    assert (steps.fragment_length, steps.clip_seconds) == (30, None)
    assert steps.clip_timing("Hopper").seconds == pytest.approx(0.24)
    agreeing = SessionSettings(fragment_length=250, clip_seconds=2.0)
    resolved = agreeing.for_env("Hopper")
    assert (resolved.fragment_length, resolved.clip_seconds) == (250, 2.0)


def test_disagreeing_or_too_short_clips_are_refused() -> None:
    with pytest.raises(ValueError, match="disagree"):
        SessionSettings(fragment_length=30, clip_seconds=2.0).for_env("Hopper")
    with pytest.raises(ValueError, match="at least 5"):
        SessionSettings(clip_seconds=0.1).for_env("HalfCheetah")  # 2 steps of 0.05 s
    with pytest.raises(ValueError):
        SessionSettings(clip_seconds=-1.0)


def test_sessions_stored_before_clip_seconds_keep_their_steps() -> None:
    stored = {"pool_size": 100, "fragment_length": 30, "round_seconds": 600, "seed": 0}
    settings = SessionSettings.model_validate(stored)
    assert settings.clip_seconds is None
    assert settings.clip_timing("Hopper").steps == 30
    assert settings.for_env("Hopper").fragment_length == 30
