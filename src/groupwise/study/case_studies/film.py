"""Filming an evaluated episode of a target env: an MP4 at real speed and a five-frame strip.

The strip is the paper's figure 5 (five frames of a learned behaviour side by side): five
evenly spaced frames over the `Target.moment_s` seconds of the episode with the highest sum
of per-step target scores. Frames are reproduced, not recorded: a rendering env is reset
with the episode's seed and steps its actions again (MuJoCo is deterministic, as the clips'
replay relies on, `groupwise.clips.replay`); frame t shows the state before step t.
"""

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image

from groupwise.clips.timing import clip_timing, step_seconds
from groupwise.clips.video import encode_mp4
from groupwise.envs import DEFAULT_FRAME_SIZE, TARGET_SCORE_KEY, Target, make_env
from groupwise.types import FloatArray, IntArray

STRIP_FRAMES = 5
"""Frames in a strip, as in the paper's figure 5."""
STRIP_GAP = 4
"""White pixels between the strip's frames."""


@dataclass(frozen=True)
class Film:
    """An episode's frames for the video and the strip."""

    frames: np.ndarray  # (F, H, W, 3) uint8, every `stride`-th state from the reset on
    fps: float
    """Playback frame rate, 1 / (stride · dt): real speed."""
    strip: np.ndarray  # (STRIP_FRAMES, H, W, 3) uint8
    strip_steps: IntArray  # (STRIP_FRAMES,) the state index (steps since the reset) of each
    step_seconds: float
    """dt of the env, s."""


def best_moment(step_scores: FloatArray, steps: int) -> int:
    """The first step of the `steps`-step window with the highest sum of `step_scores` (T,)
    (the earliest of equal ones; the whole episode when it is shorter)."""
    scores = np.asarray(step_scores, dtype=np.float64)
    steps = max(1, min(steps, len(scores)))
    sums = np.convolve(scores, np.ones(steps), mode="valid")
    return int(np.argmax(sums))


def strip_steps(step_scores: FloatArray, target: Target, step_seconds: float) -> IntArray:
    """State indices of the strip's frames: evenly spaced over `target.moment_s` from the
    start of the best moment (`best_moment`), both ends included."""
    steps = max(1, round(target.moment_s / step_seconds))
    steps = min(steps, len(step_scores))
    start = best_moment(step_scores, steps)
    return np.linspace(start, start + steps, STRIP_FRAMES).round().astype(np.int64)


def film_episode(
    target: Target,
    actions: np.ndarray,
    reset_seed: int,
    step_scores: FloatArray,
    size: tuple[int, int] = DEFAULT_FRAME_SIZE,
) -> Film:
    """Render the episode of `target`'s env reset with `reset_seed` and stepping `actions`
    (T, *action_shape), whose per-step target scores are `step_scores` (T,).

    Raises:
        RenderingUnavailableError: no offscreen GL backend.
        ValueError: the replay's step scores differ from `step_scores` (not the same episode).
    """
    width, height = size
    env = make_env(target.env, render_mode="rgb_array", width=width, height=height)
    try:
        env.reset(seed=reset_seed)
        dt = step_seconds(env)
        timing = clip_timing(dt, steps=max(1, len(actions)))
        wanted = strip_steps(step_scores, target, dt)
        frames, stills = [], {}
        replayed = []
        for t in range(len(actions) + 1):
            if t % timing.stride == 0 or t in wanted:
                frame = np.asarray(env.render())
                if t % timing.stride == 0:
                    frames.append(frame)
                if t in wanted:
                    stills[t] = frame
            if t < len(actions):
                replayed.append(env.step(actions[t])[4][TARGET_SCORE_KEY])
    finally:
        env.close()
    if not np.allclose(replayed, step_scores, rtol=1e-6, atol=1e-9):
        raise ValueError(f"replaying seed {reset_seed} did not reproduce the episode's scores")
    return Film(
        frames=np.stack(frames),
        fps=timing.fps,
        strip=np.stack([stills[int(t)] for t in wanted]),
        strip_steps=wanted,
        step_seconds=dt,
    )


def strip_image(strip: np.ndarray, gap: int = STRIP_GAP) -> np.ndarray:
    """The strip's frames (n, H, W, 3) side by side with `gap` white pixels between."""
    n, height, width, _ = strip.shape
    image = np.full((height, n * width + (n - 1) * gap, 3), 255, dtype=np.uint8)
    for i, frame in enumerate(strip):
        left = i * (width + gap)
        image[:, left : left + width] = frame
    return image


def write_film(film: Film, video: Path, strip: Path) -> None:
    """Write the episode as an MP4 at real speed and the strip as a PNG."""
    encode_mp4(film.frames, video, fps=film.fps)
    Image.fromarray(strip_image(film.strip)).save(strip, format="PNG")
