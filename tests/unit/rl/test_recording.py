"""PPO's own rollouts recorded for the next pool (`rl.recording`, `pool.recent`): the
windows are those of the latest rollouts, with the PPO step of the policy that played them,
and a recorded window's clip renders bit for bit as the replay of its episode."""

import dataclasses

import numpy as np
import pytest

from groupwise.clips.recipe import render_recipe, window_recipe
from groupwise.clips.replay import FrameSettings, make_render_env
from groupwise.clips.timing import clip_timing, step_seconds
from groupwise.config import PPOConfig
from groupwise.envs import make_env
from groupwise.episodes.fragments import tile_fragments
from groupwise.pool.recent import RecentRollouts, pool_ages
from groupwise.pool.sampling import sample_pool
from groupwise.rl.ppo import PPOAgent
from groupwise.rl.recording import record_rollouts, recorder_of_agent

PPO = PPOConfig(n_envs=2, n_steps=64, batch_size=64, n_epochs=1, tensorboard=False)
ROLLOUT = 2 * 64


def _agent(env: str, length: int, keep: int) -> PPOAgent:
    agent = PPOAgent(lambda: make_env(env), PPO, seed=3)
    timing = clip_timing(step_seconds(make_env(env)), steps=length)
    record_rollouts(
        agent.venv, length, timing.snapshot_offsets, keep, lambda: agent.num_timesteps, ROLLOUT
    )
    return agent


SHORT = "Pendulum-v1"  # 200-step episodes: one spans at most 4 rollouts of 64 steps an env
SPAN = 4


def test_the_windows_come_from_the_latest_rollouts_and_replay_from_their_reset():
    agent = _agent(SHORT, 10, keep=12)
    agent.learn(12 * ROLLOUT, seed=1)
    recorder = recorder_of_agent(agent)
    assert recorder is not None
    recent = recorder.recent(30)
    assert sum(len(e.trajectory) // 10 for e in recent) >= 30
    played = np.concatenate([e.policy_steps for e in recent])
    assert played.max() == 11 * ROLLOUT  # the policy of the last rollout …
    # … and no step of an episode older than the newest ones that hold the windows: the
    # episodes running now and the last finished ones began at most SPAN + 1 rollouts ago
    assert played.min() >= (11 - SPAN - 1) * ROLLOUT
    env = make_env(SHORT)
    for episode in recent:
        t = episode.trajectory
        obs, _ = env.reset(seed=t.reset_seed)
        for step in range(len(t)):
            assert np.allclose(np.asarray(obs, np.float32).reshape(-1), t.obs[step])
            obs = env.step(t.actions[step])[0]


def test_old_episodes_are_dropped_once_newer_ones_hold_enough_windows():
    agent = _agent(SHORT, 10, keep=30)
    agent.learn(16 * ROLLOUT, seed=1)
    recorder = recorder_of_agent(agent)
    assert recorder is not None
    finished = sum(steps // 10 for _, steps in recorder.finished)
    assert 30 <= finished < 30 + 20  # one 200-step episode more than needed, at most


def test_windows_since_a_policy_start_at_a_window_boundary_after_its_first_step():
    agent = _agent(SHORT, 10, keep=40)
    agent.learn(8 * ROLLOUT, seed=1)
    recorder = recorder_of_agent(agent)
    assert recorder is not None
    since = 7 * ROLLOUT  # the last rollout's policy
    recent = recorder.recent(100, since)
    assert recent  # 2 envs × 64 steps hold a dozen windows of 10 steps
    for episode in recent:
        t = episode.trajectory
        assert t.tile_from % 10 == 0
        windows = tile_fragments([t], 10)
        assert len(windows) == t.windows(10) >= 1
        # every window's first step was played since; the one before the first was not
        assert all(episode.window_policy(w.start) >= since for w in windows)
        if t.tile_from >= 10:
            assert episode.window_policy(t.tile_from - 10) < since


def test_a_fresh_pool_is_at_most_one_rollout_old():
    agent = _agent(SHORT, 10, keep=40)
    agent.learn(8 * ROLLOUT, seed=1)
    rng = np.random.default_rng(0)
    pool = sample_pool(
        lambda: make_env(SHORT),
        agent.policy(),
        20,
        10,
        rng,
        oversample=2.0,
        sources=(RecentRollouts(),),
        agent=agent,
    )
    recorder = recorder_of_agent(agent)
    assert recorder is not None
    recorded = {e.trajectory.reset_seed for e in recorder.recent(recorder.held_windows())}
    ages = pool_ages(pool, recorder, agent.num_timesteps)
    from_rollouts = np.array([f.reset_seed in recorded for f in pool.fragments])
    assert from_rollouts.any() and not from_rollouts.all()  # the last rollout, then sampled
    # the last rollout's policy has been updated once since; a sampled window is the policy now
    assert (ages[from_rollouts] == ROLLOUT).all()
    assert not ages[~from_rollouts].any()


def test_without_recorded_rollouts_the_pool_is_sampled_from_the_policy():
    agent = PPOAgent(lambda: make_env("GridWorld"), PPO, seed=3)  # nothing recorded
    pool = sample_pool(
        lambda: make_env("GridWorld"),
        agent.policy(),
        4,
        10,
        np.random.default_rng(0),
        sources=(RecentRollouts(),),
        agent=agent,
    )
    assert len(pool) == 4
    assert not pool_ages(pool, None, agent.num_timesteps).any()


@pytest.mark.parametrize("env", ["Hopper", "GridWorld"])
def test_a_recorded_window_renders_as_the_replay_of_its_episode(env):
    length = 40 if env == "Hopper" else 10
    agent = _agent(env, length, keep=4)
    agent.learn(2 * ROLLOUT, seed=2)
    recorder = recorder_of_agent(agent)
    timing = clip_timing(step_seconds(make_env(env)), steps=length)
    settings = FrameSettings(env, 32, 32)
    render_env = make_render_env(settings)
    checked = 0
    for episode in recorder.recent(4):
        trajectory = episode.trajectory
        bare = dataclasses.replace(trajectory, snapshots={})
        for fragment in tile_fragments([trajectory], length):
            recorded = window_recipe(trajectory, fragment, settings, timing)
            replayed = window_recipe(bare, fragment, settings, timing)
            # MuJoCo: every window but an episode's first from its recorded physics state
            assert (recorded.origin > 0) == (env == "Hopper" and fragment.start > 0)
            assert render_recipe(recorded, render_env) == render_recipe(replayed, render_env)
            checked += 1
    assert checked >= 4
