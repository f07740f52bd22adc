"""Clip frames come from replaying the episode (frame k shows the state of step start + k);
workers turn them into stored clips."""

import dataclasses
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from groupwise.clips.render import RenderPool
from groupwise.clips.render_jobs import ClipJob, plan_jobs, run_job
from groupwise.clips.replay import (
    FrameSettings,
    ReplayMismatchError,
    episode_actions,
    episode_arrays,
    make_render_env,
    replay_windows,
)
from groupwise.clips.store import ClipStore
from groupwise.clips.video import probe, read_frames
from groupwise.envs import make_env
from groupwise.envs.gridworld import draw_grid
from groupwise.episodes.fragments import Trajectory, tile_fragments
from groupwise.rl.policy import RandomPolicy
from groupwise.rl.rollout import sample_trajectories

SIZE = 48
SETTINGS = FrameSettings("GridWorld", width=SIZE, height=SIZE)


def _episodes(n: int, seed: int = 0) -> list[Trajectory]:
    env = make_env("GridWorld")
    policy = RandomPolicy(env.action_space)
    return sample_trajectories(
        lambda: make_env("GridWorld"), policy, n, np.random.default_rng(seed), max_steps=100
    )


def test_replayed_observations_equal_the_stored_ones_and_frames_show_them() -> None:
    trajectory = _episodes(1)[0]
    fragments = tile_fragments([trajectory], 10)
    chosen = [fragments[1], fragments[4]]
    env = make_render_env(SETTINGS)
    windows = dict(
        replay_windows(
            env,
            trajectory.reset_seed,
            trajectory.actions,
            [f.start for f in chosen],
            10,
            observations=trajectory.obs,  # checked step by step
        )
    )
    for fragment in chosen:
        frames = windows[fragment.start]
        assert frames.shape == (10, SIZE, SIZE, 3)
        for k, obs in enumerate(fragment.obs):
            # the GridWorld frame is a pure function of the observation (agent, target)
            expected = draw_grid(5, obs[:2].astype(int), obs[2:].astype(int), SIZE, SIZE)
            np.testing.assert_array_equal(frames[k], expected)


def test_replay_with_other_actions_is_caught() -> None:
    trajectory = _episodes(1)[0]
    actions = np.asarray(trajectory.actions).copy()
    moving = np.flatnonzero(actions[:30] != 0)[0]
    actions[moving] = 0  # "stay" instead of a move: the next observation differs
    env = make_render_env(SETTINGS)
    with pytest.raises(ReplayMismatchError, match="before step"):
        list(replay_windows(env, trajectory.reset_seed, actions, [20], 10, trajectory.obs))


def test_plan_splits_episodes_so_every_worker_has_jobs() -> None:
    episodes = _episodes(2)
    fragments = tile_fragments(episodes, 10)  # 2 x 10 windows
    jobs = plan_jobs(episodes, fragments, SETTINGS, workers=2)
    assert len(jobs) >= 4
    covered = sorted((job.episode, s) for job in jobs for s in job.starts)
    assert covered == sorted((f.episode, f.start) for f in fragments)
    for job in jobs:  # a job carries the actions and observations up to its last frame
        assert len(job.actions) == job.starts[-1] + job.length - 1
        assert len(job.observations) == len(job.actions) + 1
    assert [job.cost for job in jobs] == sorted((job.cost for job in jobs), reverse=True)


def test_plan_rejects_fragments_without_their_episode() -> None:
    episodes = _episodes(2)
    fragments = tile_fragments(episodes, 10)
    with pytest.raises(ValueError, match="no trajectory"):
        plan_jobs(episodes[:1], fragments, SETTINGS, workers=1)


def _job(episode: Trajectory, starts: tuple[int, ...], length: int) -> ClipJob:
    last = starts[-1] + length - 1
    return ClipJob(
        SETTINGS,
        episode.episode,
        episode.reset_seed,
        episode.actions[:last],
        episode.obs[: last + 1],
        starts,
        length,
    )


def test_a_job_stores_one_clip_and_poster_per_window(tmp_path: Path) -> None:
    episode = _episodes(1)[0]
    fragments = tile_fragments([episode], 10)[:3]
    job = _job(episode, (0, 10, 20), 10)
    store = ClipStore(tmp_path)
    report = run_job(job, store, make_render_env(SETTINGS))
    assert [c.start for c in report.clips] == [0, 10, 20]
    for clip in report.clips:
        assert probe(store.path(clip.clip)).frames == 10
        assert store.path(clip.poster).suffix == ".jpg"
    assert report.render_s > 0 and report.ffmpeg_cpu_s > 0
    # no temporary files are left behind
    assert not list((store.root / ".tmp").iterdir())
    # the decoded clip shows the fragment's window
    decoded = read_frames(store.path(report.clips[1].clip))
    obs = fragments[1].obs[0]
    expected = draw_grid(5, obs[:2].astype(int), obs[2:].astype(int), SIZE, SIZE)
    assert np.abs(decoded[0].astype(int) - expected).mean() < 8


def test_a_job_tells_each_clip_as_it_is_done(tmp_path: Path) -> None:
    episode = _episodes(1)[0]
    told: list[int] = []
    run_job(
        _job(episode, (0, 10, 20), 10),
        ClipStore(tmp_path),
        make_render_env(SETTINGS),
        on_clip=lambda: told.append(len(list(ClipStore(tmp_path).root.rglob("*.jpg")))),
    )
    assert told == [1, 2, 3]  # each told once its poster is stored


def test_render_workers_report_every_clip_and_progress_ends_at_all(tmp_path: Path) -> None:
    """Workers report clips over a queue as they finish them, not only whole jobs (issue 23:
    the bar did not move while clips rendered); progress ends at all of them."""
    episodes = _episodes(2, seed=1)
    jobs = [_job(episodes[0], (0, 10, 20), 10), _job(episodes[1], (5, 40), 10)]
    reports: list[tuple[int, int]] = []
    with RenderPool(1) as pool:
        pool.warm_up(SETTINGS)
        pool.render(jobs, ClipStore(tmp_path / "a"), False, lambda *r: reports.append(r))
        pool.render(jobs, ClipStore(tmp_path / "b"), False)  # its late reports are dropped
        again = pool.start(jobs, ClipStore(tmp_path / "c"))
        deadline = time.monotonic() + 60
        told = 0
        while told < 5 and time.monotonic() < deadline:
            told += again._drain()
            time.sleep(0.05)
        assert told == 5  # the worker told each of the 5 clips of this batch
    done = [d for d, _ in reports]
    assert reports[0] == (0, 5) and reports[-1] == (5, 5) and done == sorted(set(done))


def test_same_job_gives_the_same_clip_ids(tmp_path: Path) -> None:
    episode = _episodes(1, seed=3)[0]
    job = _job(episode, (10, 30), 10)
    first = run_job(job, ClipStore(tmp_path / "a"), make_render_env(SETTINGS))
    second = run_job(job, ClipStore(tmp_path / "b"), make_render_env(SETTINGS))
    assert first.clips == second.clips


def test_cheaper_clip_geometry_changes_neither_physics_nor_the_picture() -> None:
    settings = FrameSettings("Hopper", width=96, height=96)
    cheap = make_render_env(settings)  # coarser floor grid and tessellation
    plain = make_env("Hopper", render_mode="rgb_array", width=96, height=96)
    cheap_base: Any = cheap.unwrapped
    plain_base: Any = plain.unwrapped
    assert cheap_base.model.geom_size[0, 2] > plain_base.model.geom_size[0, 2]
    rng = np.random.default_rng(0)
    obs_a, _ = cheap.reset(seed=4)
    obs_b, _ = plain.reset(seed=4)
    for _ in range(10):
        action = rng.uniform(-1, 1, size=3)
        obs_a, obs_b = cheap.step(action)[0], plain.step(action)[0]
    np.testing.assert_array_equal(obs_a, obs_b)
    difference = np.abs(
        np.asarray(cheap.render(), dtype=int) - np.asarray(plain.render(), dtype=int)
    )
    assert difference.mean() < 0.5
    cheap.close()
    plain.close()


def test_windows_of_episodes_of_different_lengths_replay_to_their_ends(tmp_path: Path) -> None:
    # the standard Hopper-v5 ends when it falls: a random policy's episodes differ in length
    settings = FrameSettings("Hopper-v5", width=32, height=32)
    episodes = sample_trajectories(
        lambda: make_env("Hopper-v5"),
        RandomPolicy(make_env("Hopper-v5").action_space),
        6,
        np.random.default_rng(2),
    )
    lengths = [len(t) for t in episodes]
    assert len(set(lengths)) > 1 and max(lengths) < 1000
    fragments = tile_fragments(episodes, 3)
    assert any(f.start + 3 == lengths[f.episode] for f in fragments)  # ends at the fall
    # the episodes as a pool stores them (padded to the longest) give each one's actions back
    np.savez(tmp_path / "episodes.npz", **episode_arrays(episodes))
    stored = np.load(tmp_path / "episodes.npz")
    np.testing.assert_array_equal(stored["length"], lengths)
    replayed = [
        dataclasses.replace(t, actions=episode_actions(stored, t.episode)) for t in episodes
    ]
    for t, again in zip(episodes, replayed, strict=True):
        np.testing.assert_array_equal(again.actions, t.actions)
    env = make_render_env(settings)
    jobs = plan_jobs(replayed, fragments, settings, workers=1)
    rendered = {
        (job.episode, start): frames
        for job in jobs
        for start, frames in replay_windows(
            env, job.reset_seed, job.actions, job.starts, job.length, job.observations
        )  # every observation checked against the stored one
    }
    assert sorted(rendered) == sorted((f.episode, f.start) for f in fragments)
    assert all(frames.shape == (3, 32, 32, 3) for frames in rendered.values())
    env.close()


def test_strided_windows_show_every_kth_frame_of_the_unstrided_ones() -> None:
    # Hopper plays at real speed with a frame every 4th step of 0.008 s (clips.timing)
    settings = FrameSettings("Hopper", width=32, height=32)
    episode = sample_trajectories(
        lambda: make_env("Hopper"),
        RandomPolicy(make_env("Hopper").action_space),
        1,
        np.random.default_rng(5),
        max_steps=60,
    )[0]
    env = make_render_env(settings)
    starts, length = [3, 30], 23
    every = dict(replay_windows(env, episode.reset_seed, episode.actions, starts, length))
    strided = dict(
        replay_windows(
            env, episode.reset_seed, episode.actions, starts, length, episode.obs, stride=4
        )
    )
    for start in starts:
        assert every[start].shape[0] == length
        assert strided[start].shape == (6, 32, 32, 3)  # ⌈23 / 4⌉
        np.testing.assert_array_equal(strided[start], every[start][::4])
    with pytest.raises(ValueError, match="stride"):
        list(replay_windows(env, episode.reset_seed, episode.actions, starts, length, stride=0))
    env.close()


def test_a_strided_job_stores_clips_of_its_frames_at_its_rate(tmp_path: Path) -> None:
    episode = _episodes(1)[0]
    job = dataclasses.replace(_job(episode, (0, 10), 10), stride=3, fps=12.5)
    assert job.clip_frames == 4 and job.frames == 8
    store = ClipStore(tmp_path)
    report = run_job(job, store, make_render_env(SETTINGS))
    for clip in report.clips:
        info = probe(store.path(clip.clip))
        assert info.frames == 4 and info.fps == 12.5
    decoded = read_frames(store.path(report.clips[1].clip))
    obs = episode.obs[10 + 2 * 3]  # frame 2 of the window at 10
    expected = draw_grid(5, obs[:2].astype(int), obs[2:].astype(int), SIZE, SIZE)
    assert np.abs(decoded[2].astype(int) - expected).mean() < 8


@pytest.mark.parametrize(
    ("env", "shape"),
    [
        ("Pendulum-v1", (240, 240, 3)),  # drawn 500 × 500 by Gymnasium (issue 23)
        ("CartPole-v1", (160, 240, 3)),  # 600 × 400: fitted, its aspect kept
    ],
)
def test_envs_that_take_no_frame_size_render_the_requested_one(env: str, shape: tuple) -> None:
    rendering = make_render_env(FrameSettings(env, width=240, height=240))
    try:
        rendering.reset(seed=0)
        assert np.asarray(rendering.render()).shape == shape
    finally:
        rendering.close()


def test_a_pendulum_clip_has_the_frame_size(tmp_path: Path) -> None:
    settings = FrameSettings("Pendulum-v1", width=96, height=96)
    episode = sample_trajectories(
        lambda: make_env("Pendulum-v1"),
        RandomPolicy(make_env("Pendulum-v1").action_space),
        1,
        np.random.default_rng(0),
    )[0]
    job = dataclasses.replace(_job(episode, (0, 10), 10), settings=settings)
    report = run_job(job, ClipStore(tmp_path))
    video = probe(ClipStore(tmp_path).path(report.clips[0].clip))
    assert (video.width, video.height) == (96, 96)
