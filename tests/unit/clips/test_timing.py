"""A behaviour covers simulated seconds; its clip plays them at real speed."""

import math

import pytest

from groupwise.clips.timing import (
    DEFAULT_CLIP_SECONDS,
    ClipTiming,
    clip_timing,
    default_clip_seconds,
    env_clip_timing,
    env_step_seconds,
)


@pytest.mark.parametrize(
    ("dt", "seconds", "steps", "stride", "frames", "fps"),
    [
        (0.008, 1.5, 188, 4, 47, 31.25),  # Hopper, Walker2d: 1 / (30 · 0.008) = 4.17 → 4
        (0.05, 1.5, 30, 1, 30, 20.0),  # HalfCheetah: coarser than 30 frames/s, every step
        (0.02, 1.0, 50, 2, 25, 25.0),  # Reacher: 1 / (30 · 0.02) = 1.67 → 2
        (1 / 30, 1.0, 30, 1, 30, 30.0),  # GridWorld, classic control: one frame per step
        (0.001, 0.5, 500, 33, 16, 1000 / 33),  # fine physics: every 33rd step
    ],
)
def test_timing_by_hand(
    dt: float, seconds: float, steps: int, stride: int, frames: int, fps: float
) -> None:
    timing = clip_timing(dt, seconds)
    assert (timing.steps, timing.stride, timing.frames) == (steps, stride, frames)
    assert timing.fps == pytest.approx(fps)
    assert timing.seconds == pytest.approx(steps * dt)
    assert timing.speed == pytest.approx(1.0)


def test_a_given_number_of_steps_keeps_the_stride_of_its_env() -> None:
    timing = clip_timing(0.008, steps=30)  # the study's L = 30 on Hopper: 0.24 s
    assert (timing.steps, timing.stride, timing.frames) == (30, 4, 8)
    assert timing.seconds == pytest.approx(0.24)
    assert timing.speed == pytest.approx(1.0)


def test_frames_cover_every_step_of_the_window() -> None:
    for steps in range(1, 40):
        for stride in range(1, 6):
            timing = ClipTiming(0.01, steps, stride)
            shown = [j * stride for j in range(timing.frames)]
            assert shown[-1] < steps <= shown[-1] + stride  # the last frame is in the window


def test_bad_timings_are_refused() -> None:
    with pytest.raises(ValueError, match="either"):
        clip_timing(0.01)
    with pytest.raises(ValueError, match="either"):
        clip_timing(0.01, 1.0, steps=10)
    with pytest.raises(ValueError, match="positive"):
        clip_timing(0.0, 1.0)
    with pytest.raises(ValueError, match="positive"):
        clip_timing(0.01, -1.0)
    with pytest.raises(ValueError, match=">= 1"):
        ClipTiming(0.01, 0, 1)


def test_timing_as_json_is_what_pools_record() -> None:
    assert clip_timing(0.008, 1.5).as_json() == {
        "steps": 188,
        "stride": 4,
        "frames": 47,
        "fps": 31.25,
        "seconds": 1.504,
        "speed": 1.0,
        "step_seconds": 0.008,
    }


@pytest.mark.parametrize(
    ("env", "dt", "steps", "stride", "fps"),
    [
        ("Hopper", 0.008, 188, 4, 31.25),
        ("Walker2d", 0.008, 188, 4, 31.25),
        ("HalfCheetah", 0.05, 30, 1, 20.0),
        ("Reacher", 0.02, 50, 2, 25.0),
        ("MountainCarContinuous", 1 / 30, 60, 1, 30.0),
        ("GridWorld", 1 / 30, 30, 1, 30.0),
    ],
)
def test_each_env_has_a_default_clip_at_real_speed(
    env: str, dt: float, steps: int, stride: int, fps: float
) -> None:
    assert env_step_seconds(env) == pytest.approx(dt)
    timing = env_clip_timing(env)
    assert (timing.steps, timing.stride) == (steps, stride)
    assert timing.fps == pytest.approx(fps)
    assert 1.0 <= timing.seconds <= 2.1
    assert math.isclose(timing.seconds, default_clip_seconds(env), rel_tol=0.01)


def test_other_envs_get_the_default_duration() -> None:
    assert default_clip_seconds("Pendulum-v1") == DEFAULT_CLIP_SECONDS
    timing = env_clip_timing("Pendulum-v1")  # dt 0.05 s
    assert (timing.steps, timing.stride, timing.fps) == (20, 1, pytest.approx(20.0))
    assert env_clip_timing("Hopper", steps=30).steps == 30


@pytest.mark.parametrize("env", ["Swimmer-v5", "Swimmer-v4"])
def test_a_swimmers_clips_last_long_enough_to_see_it_swim(env: str) -> None:
    """1 s of Swimmer is 25 steps in which it barely moves (issue 23): 4 s, 100 steps."""
    assert default_clip_seconds(env) == 4.0
    if env == "Swimmer-v5":
        timing = env_clip_timing(env)  # dt 0.04 s
        assert (timing.steps, timing.stride, timing.fps) == (100, 1, pytest.approx(25.0))
