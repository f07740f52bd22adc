"""The DeepMind Control suite through Shimmy (optional extra groupwise[dmc], issue 42): the
suite's horizon, flat observations, clip frames replayed offscreen, a session's settings."""

import sys

import numpy as np
import pytest

from groupwise.envs import horizon, make_env, resolve_id

WALKER = "dm_control/walker-walk-v0"


def test_without_shimmy_a_suite_id_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "shimmy", None)  # `import shimmy` raises ImportError
    with pytest.raises(ValueError) as caught:
        resolve_id("dm_control/no_such-task-v0")
    message = str(caught.value)
    assert "needs the DeepMind Control suite: pip install 'groupwise[dmc]'" in message
    assert "\n" not in message


@pytest.fixture
def suite() -> None:
    pytest.importorskip("shimmy", reason="the DeepMind Control suite needs groupwise[dmc]")
    pytest.importorskip("dm_control", reason="the DeepMind Control suite needs groupwise[dmc]")


@pytest.mark.usefixtures("suite")
def test_an_episode_lasts_the_suites_1000_steps_and_ends_truncated() -> None:
    assert horizon(WALKER) == horizon("dm_control/cheetah-run-v0") == 1000
    env = make_env(WALKER)
    env.reset(seed=0)
    env.action_space.seed(0)
    steps, truncated = 0, False
    while not truncated and steps < 1001:
        _, reward, terminated, truncated, info = env.step(env.action_space.sample())
        steps += 1
        assert not terminated and 0.0 <= reward <= 1.0
    assert steps == 1000 and truncated
    assert int(info["timestep.step_type"]) == 2  # dm_env's StepType.LAST: dm_control ended it


@pytest.mark.usefixtures("suite")
def test_an_unknown_suite_task_is_one_line() -> None:
    with pytest.raises(ValueError, match="unknown env 'dm_control/walker-fly-v0'"):
        make_env("dm_control/walker-fly-v0")


@pytest.mark.usefixtures("suite")
def test_a_window_replays_into_offscreen_frames_of_the_requested_size() -> None:
    from groupwise.clips.replay import FrameSettings, make_render_env, replay_windows
    from groupwise.envs.rendering import frame_is_blank
    from groupwise.rl.policy import RandomPolicy
    from groupwise.rl.rollout import sample_trajectories

    policy = RandomPolicy(make_env(WALKER).action_space)
    (episode,) = sample_trajectories(
        lambda: make_env(WALKER), policy, 1, np.random.default_rng(4), max_steps=120
    )
    assert episode.obs.shape == (120, 24)  # the observation before each step
    env = make_render_env(FrameSettings(WALKER, width=64, height=48))
    frames = dict(replay_windows(env, episode.reset_seed, episode.actions, [100], 10, episode.obs))[
        100
    ]
    assert frames.shape == (10, 48, 64, 3) and frames.dtype == np.uint8
    assert not frame_is_blank(frames[0]) and not np.array_equal(frames[0], frames[-1])


@pytest.mark.usefixtures("suite")
def test_a_session_of_a_suite_task_gets_its_behaviour_length_from_the_control_step() -> None:
    from groupwise.server.state import check_env
    from groupwise.storage import SessionSettings

    settings = check_env(WALKER, SessionSettings.model_validate({"clip_seconds": 1.0}))
    assert settings.fragment_length == 40  # 1 s of 0.025 s control steps
