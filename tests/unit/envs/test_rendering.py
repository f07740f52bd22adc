"""Rendering: every env draws a non-blank frame of the requested size, offscreen and fast."""

import gc
import os
import subprocess
import sys
from typing import Any

import gymnasium as gym
import mujoco
import numpy as np
import pytest

from groupwise.envs import ENVS, RenderingUnavailableError, make_env, rendering


def _distinct_colours(frame: np.ndarray) -> int:
    return len(np.unique(frame.reshape(-1, frame.shape[-1]), axis=0))


@pytest.mark.parametrize("name", list(ENVS))
def test_each_env_renders_a_non_blank_frame_of_the_requested_size(name: str) -> None:
    env = make_env(name, render_mode="rgb_array", width=160, height=120)
    env.reset(seed=0)
    env.step(env.action_space.sample())
    frame = env.render()
    assert frame.shape == (120, 160, 3) and frame.dtype == np.uint8
    assert frame.std() > 10.0
    assert _distinct_colours(frame) > 3
    assert not rendering.frame_is_blank(frame)


def test_default_frame_size_is_240() -> None:
    env = make_env("Hopper", render_mode="rgb_array")
    env.reset(seed=0)
    assert env.render().shape == (240, 240, 3)


def _viewer(env: gym.Env[Any, Any]) -> Any:
    base: Any = env.unwrapped
    return base.mujoco_renderer.viewer


def test_fast_settings_are_applied() -> None:
    env = make_env("Walker2d", render_mode="rgb_array")
    env.reset(seed=0)
    env.render()
    model = env.unwrapped.model
    assert model.vis.quality.offsamples == 0
    flags = _viewer(env).scn.flags
    for flag in ("mjRND_SHADOW", "mjRND_REFLECTION", "mjRND_SKYBOX"):
        assert flags[getattr(mujoco.mjtRndFlag, flag)] == 0


def test_camera_tracks_the_hopper_torso() -> None:
    env = make_env("Hopper", render_mode="rgb_array")
    env.reset(seed=0)
    base: Any = env.unwrapped
    qpos = base.data.qpos.copy()
    qpos[0] += 5.0
    base.set_state(qpos, base.data.qvel)
    frame = env.render()
    torso = mujoco.mj_name2id(base.model, mujoco.mjtObj.mjOBJ_BODY, "torso")
    np.testing.assert_allclose(_viewer(env).cam.lookat, base.data.subtree_com[torso], atol=1e-6)
    # The robot's orange fills part of the centre column of the frame.
    centre = frame[:, 100:140].astype(int)
    orange = (centre[..., 0] > 150) & (centre[..., 2] < 100)
    assert orange.sum() > 50


def test_envs_sharing_a_process_do_not_blank_each_other() -> None:
    first = make_env("Reacher", render_mode="rgb_array")
    first.reset(seed=0)
    assert not rendering.frame_is_blank(first.render())
    second = make_env("HalfCheetah", render_mode="rgb_array")
    second.reset(seed=0)
    assert not rendering.frame_is_blank(second.render())
    # Freeing a GL context releases whichever context is current, here the cheetah's.
    first.close()
    del first
    assert not rendering.frame_is_blank(second.render())
    third = make_env("Reacher", render_mode="rgb_array")
    third.reset(seed=0)
    assert not rendering.frame_is_blank(third.render())
    del third  # dropped without close: the garbage collector frees it
    gc.collect()
    assert not rendering.frame_is_blank(second.render())


def test_other_gymnasium_envs_render_too() -> None:
    pendulum = make_env("InvertedPendulum-v5", render_mode="rgb_array", width=64, height=48)
    pendulum.reset(seed=0)
    assert pendulum.render().shape == (48, 64, 3)
    assert pendulum.unwrapped.model.vis.quality.offsamples == 0
    cartpole = make_env("CartPole-v1", render_mode="rgb_array")
    cartpole.reset(seed=0)
    assert not rendering.frame_is_blank(cartpole.render())


def test_user_choice_of_backend_is_respected(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MUJOCO_GL", "osmesa")
    monkeypatch.setattr(rendering, "_backend_works", lambda backend: pytest.fail("probed"))
    assert rendering.ensure_gl_backend() == "osmesa"


def test_falls_back_to_osmesa_when_egl_fails(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("MUJOCO_GL", raising=False)
    monkeypatch.delenv("PYOPENGL_PLATFORM", raising=False)
    tried: list[str] = []

    def works(backend: str) -> bool:
        tried.append(backend)
        return backend == "osmesa"

    monkeypatch.setattr(rendering, "_backend_works", works)
    assert rendering.ensure_gl_backend() == "osmesa"
    assert tried == ["egl", "osmesa"]
    assert os.environ["MUJOCO_GL"] == "osmesa"


def test_no_backend_names_the_packages_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("MUJOCO_GL", raising=False)
    monkeypatch.delenv("PYOPENGL_PLATFORM", raising=False)
    monkeypatch.setattr(rendering, "_backend_works", lambda backend: False)
    with pytest.raises(RenderingUnavailableError) as caught:
        rendering.ensure_gl_backend()
    assert "libegl1 libgl1-mesa-dri" in str(caught.value)
    assert "libosmesa6" in str(caught.value)


def test_failing_gl_context_gives_a_clear_error(monkeypatch: pytest.MonkeyPatch) -> None:
    env = make_env("Reacher", render_mode="rgb_array")
    env.reset(seed=0)

    def no_context(mode: str) -> None:
        raise RuntimeError("Cannot create an EGL context.")

    base: Any = env.unwrapped
    monkeypatch.setattr(base.mujoco_renderer, "_get_viewer", no_context)
    monkeypatch.setenv("MUJOCO_GL", "egl")
    with pytest.raises(RenderingUnavailableError, match="MUJOCO_GL='egl'") as caught:
        env.render()
    assert "libegl1 libgl1-mesa-dri" in str(caught.value)


_PENDULUM_FRAME = """
from groupwise.envs import make_env
env = make_env("Pendulum-v1", render_mode="rgb_array")
env.reset(seed=0)
print(env.render().shape)
"""


def test_a_classic_control_frame_renders_without_desktop_warnings() -> None:
    # as the app's worker would: no desktop session, no SDL settings of the user's
    scrubbed = ("XDG_RUNTIME_DIR", "DISPLAY", "WAYLAND_DISPLAY", *rendering.HEADLESS_SDL)
    env = {k: v for k, v in os.environ.items() if k not in scrubbed}
    result = subprocess.run(
        [sys.executable, "-c", _PENDULUM_FRAME],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "(500, 500, 3)"  # Pendulum draws at its own size
    assert "XDG_RUNTIME_DIR" not in result.stderr, result.stderr
    assert "pygame" not in result.stdout + result.stderr  # no greeting either


def test_headless_sdl_leaves_the_users_choice(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("SDL_VIDEODRIVER", "x11")
    monkeypatch.delenv("SDL_AUDIODRIVER", raising=False)
    rendering.use_headless_sdl()
    assert os.environ["SDL_VIDEODRIVER"] == "x11"
    assert os.environ["SDL_AUDIODRIVER"] == "dummy"


def test_frames_are_fitted_into_the_box_keeping_their_aspect():
    assert rendering.fit_size((500, 500), (240, 240)) == (240, 240)
    assert rendering.fit_size((600, 400), (240, 240)) == (240, 160)
    assert rendering.fit_size((64, 32), (240, 240)) == (240, 120)  # enlarged too
    assert rendering.fit_size((1000, 2), (100, 100)) == (100, 2)  # never thinner than 2 pixels
