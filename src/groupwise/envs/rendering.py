"""Offscreen rendering: choosing MuJoCo's GL backend and rendering MuJoCo envs fast on a CPU,
and keeping pygame (Gymnasium's classic-control renderer) away from the desktop.

No function here ever needs an X server. MuJoCo renders through EGL or OSMesa, chosen once per
process by `ensure_gl_backend` (the choice is stored in ``MUJOCO_GL`` so that worker processes
inherit it). `FastMujocoRendering` wraps a MuJoCo env so that its frames are rendered without
shadows, reflections, skybox and multisampling (Hopper at 240×240 with EGL on a CPU: ~9 → ~150
frames/s, see ``benchmarks/render_fps.py``), optionally with a camera that tracks a body, and
always with its own GL context current.
"""

import logging
import os
import subprocess
import sys
from typing import Any

import gymnasium as gym
import mujoco
import numpy as np
from gymnasium.envs.mujoco.mujoco_env import MujocoEnv
from PIL import Image

logger = logging.getLogger(__name__)

DEFAULT_FRAME_SIZE: tuple[int, int] = (240, 240)
"""(width, height) in pixels of the frames our envs render unless told otherwise."""

GL_BACKENDS: tuple[str, ...] = ("egl", "osmesa")
"""Offscreen backends tried, in order, when ``MUJOCO_GL`` is not set."""

DEBIAN_PACKAGES: dict[str, str] = {"egl": "libegl1 libgl1-mesa-dri", "osmesa": "libosmesa6"}
"""The Debian/Ubuntu packages each backend needs, named in the error when none works."""

OFFSCREEN_MODES = frozenset({"rgb_array", "depth_array", "rgbd_tuple"})
"""Render modes that draw into an offscreen buffer (everything but "human")."""

# Checked in a fresh interpreter: once PyOpenGL has loaded one platform in a process it cannot
# switch to another, so a failed in-process EGL attempt would also spoil the OSMesa fallback.
_PROBE = """
import mujoco
from mujoco.{backend} import GLContext
context = GLContext(16, 16)
context.make_current()
mujoco.MjrContext(mujoco.MjModel.from_xml_string("<mujoco/>"), mujoco.mjtFontScale.mjFONTSCALE_100)
context.free()
"""


HEADLESS_SDL: dict[str, str] = {
    "SDL_VIDEODRIVER": "dummy",
    "SDL_AUDIODRIVER": "dummy",
    "PYGAME_HIDE_SUPPORT_PROMPT": "1",
}
"""What `use_headless_sdl` sets, unless the user set it: SDL draws into memory and plays no
sound, and pygame prints no greeting."""


def use_headless_sdl() -> None:
    """Make pygame render offscreen, quietly, in this process and the ones it starts.

    Gymnasium's classic-control envs (Pendulum-v1, MountainCar, CartPole, ...) draw their
    ``rgb_array`` frames with pygame, whose SDL would probe the desktop's video drivers: with
    no Wayland session it prints "XDG_RUNTIME_DIR is invalid or not set in the environment"
    on stderr (once per process: three times for ``groupwise serve --env Pendulum-v1``, the
    worker and its two render processes), and with ``$DISPLAY`` set it connects to the X
    server. Each variable of `HEADLESS_SDL` is set only when unset, so a user's choice
    stands. SDL reads them when pygame's display is first initialised, so this must run
    before an env's first frame; spawned processes inherit them.
    """
    for key, value in HEADLESS_SDL.items():
        os.environ.setdefault(key, value)


class RenderingUnavailableError(RuntimeError):
    """No offscreen OpenGL backend works in this process (a system library is missing)."""


def _missing_packages_message(tried: list[str]) -> str:
    hints = "; ".join(f"{name}: apt-get install {DEBIAN_PACKAGES[name]}" for name in tried)
    return (
        f"no offscreen OpenGL backend works for MuJoCo (tried {', '.join(tried)}); "
        f"install the system packages for one of them ({hints}) or set MUJOCO_GL"
    )


def _backend_works(backend: str) -> bool:
    """Whether MuJoCo can create a `backend` GL context, checked in a child interpreter."""
    env = {**os.environ, "MUJOCO_GL": backend, "PYOPENGL_PLATFORM": backend}
    try:
        result = subprocess.run(
            [sys.executable, "-c", _PROBE.format(backend=backend)],
            env=env,
            capture_output=True,
            timeout=120,
            check=False,
        )
    except (OSError, subprocess.TimeoutExpired) as error:
        logger.debug("probing MUJOCO_GL=%s failed: %s", backend, error)
        return False
    if result.returncode != 0:
        logger.debug("MUJOCO_GL=%s unusable: %s", backend, result.stderr.decode()[-500:])
    return result.returncode == 0


def ensure_gl_backend() -> str:
    """Choose MuJoCo's offscreen GL backend for this process and return its name.

    Respects ``MUJOCO_GL`` when the user set it. Otherwise tries EGL, then OSMesa (only the
    one named by ``PYOPENGL_PLATFORM`` if that is set), each in a child interpreter, and
    stores the first that works in ``os.environ["MUJOCO_GL"]`` (so later calls and worker
    processes skip the probe). Must run before MuJoCo's GL is first used in the process.
    (With ``MUJOCO_GL`` set, ``import mujoco`` itself loads that backend, so a value naming a
    library that is not installed already fails there, before this function can help.)

    Raises:
        RenderingUnavailableError: no backend works; the message names the Debian packages
            to install (EGL: libegl1 libgl1-mesa-dri; OSMesa: libosmesa6).
    """
    chosen = os.environ.get("MUJOCO_GL")
    if chosen:
        return chosen
    platform = os.environ.get("PYOPENGL_PLATFORM", "").lower()
    candidates = [platform] if platform in GL_BACKENDS else list(GL_BACKENDS)
    for backend in candidates:
        if _backend_works(backend):
            os.environ["MUJOCO_GL"] = backend
            logger.info("rendering MuJoCo offscreen with MUJOCO_GL=%s", backend)
            return backend
    raise RenderingUnavailableError(_missing_packages_message(candidates))


def apply_fast_model_settings(model: mujoco.MjModel, width: int, height: int) -> None:
    """Turn multisampling off and size the offscreen buffer to at least `width`×`height`.

    Must be applied before the model's GL context is created (MuJoCo reads ``offsamples``
    when it allocates the offscreen buffer).
    """
    model.vis.quality.offsamples = 0
    model.vis.global_.offwidth = max(model.vis.global_.offwidth, width)
    model.vis.global_.offheight = max(model.vis.global_.offheight, height)


def apply_fast_scene_flags(scene: mujoco.MjvScene) -> None:
    """Turn off the scene effects that dominate CPU rendering time (shadows, reflections, sky)."""
    scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = 0
    scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = 0
    scene.flags[mujoco.mjtRndFlag.mjRND_SKYBOX] = 0


def track_body(camera: mujoco.MjvCamera, model: mujoco.MjModel, body: str) -> None:
    """Point `camera` at `body`'s subtree centre of mass and follow it (keeping the distance,
    azimuth and elevation already set)."""
    body_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, body)
    if body_id < 0:
        raise ValueError(f"model has no body named {body!r} to track")
    camera.type = mujoco.mjtCamera.mjCAMERA_TRACKING
    camera.trackbodyid = body_id


class FastMujocoRendering(gym.Wrapper[Any, Any, Any, Any]):
    """Renders a Gymnasium MuJoCo env offscreen with the fast settings of this module.

    On construction: chooses the GL backend (`ensure_gl_backend`) and applies
    `apply_fast_model_settings`; on the first offscreen `render`: creates the viewer, applies
    `apply_fast_scene_flags` and, if `tracked_body` is given, a tracking camera. Before every
    frame it makes this env's GL context current, and on `close` (or garbage collection) it
    frees its GL objects under its own context: Gymnasium does neither, so another MuJoCo env
    in the same process that creates its context or is freed would make this one render black.
    Frames are (height, width, 3) uint8. "human" rendering passes through untouched.
    """

    def __init__(self, env: gym.Env[Any, Any], tracked_body: str | None = None) -> None:
        super().__init__(env)
        base = env.unwrapped
        if not isinstance(base, MujocoEnv):
            raise TypeError(f"FastMujocoRendering needs a MujocoEnv, got {type(base).__name__}")
        self._base: MujocoEnv = base
        self._tracked_body = tracked_body
        self._viewer: Any = None
        if env.render_mode in OFFSCREEN_MODES:
            ensure_gl_backend()
            apply_fast_model_settings(base.model, base.width, base.height)

    def render(self) -> Any:
        """Render one frame (see the class docstring for what differs from Gymnasium)."""
        mode = self.env.render_mode
        if mode not in OFFSCREEN_MODES:
            return self.env.render()
        renderer = self._base.mujoco_renderer
        try:
            # Gymnasium offers no public hook between creating a viewer and its first frame.
            viewer = renderer._get_viewer(mode)
        except Exception as error:
            if self._viewer is not None:
                raise
            backend = os.environ.get("MUJOCO_GL", "")
            tried = [backend] if backend in DEBIAN_PACKAGES else list(GL_BACKENDS)
            raise RenderingUnavailableError(
                f"MuJoCo could not create a GL context with MUJOCO_GL={backend!r} ({error}); "
                + _missing_packages_message(tried)
            ) from error
        if viewer is not self._viewer:
            self._configure(renderer, viewer)
        viewer.make_context_current()
        return self.env.render()

    def close(self) -> None:
        """Free this env's GL objects under its own context, then close the env."""
        self._free_gl_objects()
        super().close()

    def __del__(self) -> None:
        try:
            self._free_gl_objects()
        except Exception:  # interpreter shutdown or a half-built wrapper
            logger.debug("could not free MuJoCo GL objects", exc_info=True)

    def _free_gl_objects(self) -> None:
        # MuJoCo frees an MjrContext's framebuffers and textures in whichever GL context is
        # current; freed by the garbage collector under another env's context, it deletes
        # that env's offscreen framebuffer (same ids) and the other env renders black.
        viewer, self._viewer = self._viewer, None
        if viewer is not None:
            viewer.make_context_current()
            viewer.con.free()

    def _configure(self, renderer: Any, viewer: Any) -> None:
        apply_fast_scene_flags(viewer.scn)
        if self._tracked_body is not None:
            track_body(viewer.cam, self._base.model, self._tracked_body)
            # A camera id makes Gymnasium reset the camera type before every frame.
            renderer.camera_id = None
        self._viewer = viewer


def frame_is_blank(frame: np.ndarray) -> bool:
    """Whether an RGB frame is (close to) one flat colour, e.g. from a dead GL context."""
    return bool(np.asarray(frame, dtype=np.float64).std() < 1.0)


def fit_size(size: tuple[int, int], box: tuple[int, int]) -> tuple[int, int]:
    """(width, height) of a `size` (width, height) frame scaled to fit in `box`, keeping its
    aspect ratio, each side at least 2 pixels: (500, 500) in (240, 240) → (240, 240), (600, 400)
    → (240, 160)."""
    scale = min(box[0] / size[0], box[1] / size[1])
    return max(2, round(size[0] * scale)), max(2, round(size[1] * scale))


class FrameSize(gym.Wrapper[Any, Any, Any, Any]):
    """Scales an env's ``rgb_array`` frames to fit in `width` × `height`, keeping their aspect.

    For envs whose constructor takes no frame size (Gymnasium's classic control draws
    Pendulum-v1 at 500 × 500, CartPole at 600 × 400), so that a session's frame size holds
    for every env (issue 23). Frames already of the size pass untouched; smaller ones are
    enlarged (bicubic), larger ones shrunk by area averaging. Other modes pass through.
    """

    def __init__(self, env: gym.Env[Any, Any], width: int, height: int) -> None:
        super().__init__(env)
        self.box = (width, height)

    def render(self) -> Any:
        frame = self.env.render()
        if self.env.render_mode != "rgb_array" or frame is None:
            return frame
        frame = np.asarray(frame)
        height, width = frame.shape[:2]
        size = fit_size((width, height), self.box)
        if size == (width, height):
            return frame
        shrink = size[0] < width
        method = Image.Resampling.BOX if shrink else Image.Resampling.BICUBIC
        return np.asarray(Image.fromarray(frame).resize(size, method))
