"""Rendered frames per second of each groupwise env at 240×240, fast settings vs Gymnasium's.

Run: ``python benchmarks/render_fps.py [--frames 300] [--size 240]``. Prints a Markdown table.
Only `render()` is timed (stepping is not); every env steps with seeded random actions so the
scene changes between frames. The "Gymnasium default" column renders the standard v5 env with
Gymnasium's own settings (shadows, reflections, skybox, multisampling) through the same GL
backend in the same process.
"""

import argparse
import sys
import time
from collections.abc import Callable
from functools import partial
from typing import Any

import gymnasium as gym

from groupwise.envs import ENVS, make_env
from groupwise.envs.rendering import ensure_gl_backend

MUJOCO_ENVS = ("Hopper", "HalfCheetah", "Walker2d", "Reacher")
OTHER_ENVS = ("GridWorld", "MountainCarContinuous")


def frames_per_second(
    make: Callable[[], gym.Env[Any, Any]], frames: int, seed: int = 0, warm_up: int = 10
) -> float:
    """Render `frames` frames of a fresh env (after `warm_up` untimed ones), return frames/s."""
    env = make()
    try:
        env.reset(seed=seed)
        env.action_space.seed(seed)
        for _ in range(warm_up):
            env.render()
        elapsed = 0.0
        for _ in range(frames):
            env.step(env.action_space.sample())
            start = time.perf_counter()
            env.render()
            elapsed += time.perf_counter() - start
        return frames / elapsed
    finally:
        env.close()


def main(argv: list[str] | None = None) -> None:
    """Measure and print the table; `argv` holds command-line options (defaults when None)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--frames", type=int, default=300, help="frames timed per env")
    parser.add_argument("--size", type=int, default=240, help="frame width and height (px)")
    args = parser.parse_args([] if argv is None else argv)
    size = {"width": args.size, "height": args.size}
    backend = ensure_gl_backend()

    print(
        f"Rendered frames/s at {args.size}×{args.size}, {args.frames} frames each, "
        f"MUJOCO_GL={backend}\n"
    )
    print("| env | fast (groupwise) | Gymnasium default | speed-up |")
    print("|---|---:|---:|---:|")
    for name in MUJOCO_ENVS:
        standard_id = ENVS[name].standard_id
        assert standard_id is not None
        fast = frames_per_second(partial(make_env, name, "rgb_array", **size), args.frames)
        default = frames_per_second(
            partial(gym.make, standard_id, render_mode="rgb_array", **size), args.frames
        )
        print(f"| {name} | {fast:.0f} | {default:.0f} | {fast / default:.1f}× |")
    for name in OTHER_ENVS:
        fast = frames_per_second(partial(make_env, name, "rgb_array", **size), args.frames)
        print(f"| {name} | {fast:.0f} | — | — |")


if __name__ == "__main__":
    main(sys.argv[1:])
