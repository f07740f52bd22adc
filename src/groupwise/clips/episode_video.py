"""A whole episode as one MP4 at real speed: the final agent's video (docs/app.md).

The episode is reproduced, not recorded, as a clip is (`clips.replay`): a rendering env is
reset with the episode's seed and steps its actions again, every observation checked
against the stored one; frames are taken every k-th step so the video plays at real speed
(`clips.timing`). Long episodes are cut at `MAX_VIDEO_SECONDS` of simulated time: a Hopper
episode of 1000 steps is 8 s, a HalfCheetah one 50 s.
"""

import os
from dataclasses import dataclass
from pathlib import Path

from groupwise.clips.replay import FrameSettings, even_crop, make_render_env, replay_windows
from groupwise.clips.timing import clip_timing, step_seconds
from groupwise.clips.video import encode_mp4
from groupwise.episodes.fragments import Trajectory

MAX_VIDEO_SECONDS = 10.0
"""Most simulated seconds of an episode the video shows (its first ones)."""


@dataclass(frozen=True)
class EpisodeVideo:
    """What a written episode video shows."""

    steps: int
    """Env steps shown (the episode's first ones)."""
    frames: int
    fps: float
    """Playback frame rate, 1 / (stride · dt): real speed."""
    seconds: float
    """Simulated (and playback) seconds, steps · dt."""
    width: int
    height: int


def write_episode_video(
    settings: FrameSettings,
    episode: Trajectory,
    path: Path,
    max_seconds: float = MAX_VIDEO_SECONDS,
) -> EpisodeVideo:
    """Render `episode` of `settings.env` (its first `max_seconds`) as an MP4 at `path`,
    replaced atomically.

    Raises:
        RenderingUnavailableError: no offscreen GL backend.
        ReplayMismatchError: the replay does not reproduce the episode.
        ValueError: an empty episode.
    """
    if len(episode) < 1:
        raise ValueError("an empty episode has nothing to show")
    env = make_render_env(settings)
    try:
        dt = step_seconds(env)
        steps = max(1, min(len(episode), round(max_seconds / dt)))
        timing = clip_timing(dt, steps=steps)
        _, frames = next(
            replay_windows(
                env,
                episode.reset_seed,
                episode.actions,
                [0],
                steps,
                observations=episode.obs,
                stride=timing.stride,
            )
        )
    finally:
        env.close()
    frames = even_crop(frames)
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(f".{path.name}.partial")
    encode_mp4(frames, partial, settings.video, fps=timing.fps)
    os.replace(partial, path)
    return EpisodeVideo(
        steps=steps,
        frames=len(frames),
        fps=timing.fps,
        seconds=timing.seconds,
        width=int(frames.shape[2]),
        height=int(frames.shape[1]),
    )
