"""Stepping a sampling batch across processes changes nothing but the speed (issue 22)."""

import os
import threading

import gymnasium as gym
import numpy as np
import pytest

from groupwise.config import RewardConfig
from groupwise.envs import make_env
from groupwise.pool.sampling import sample_pool
from groupwise.reward import RewardEnsemble
from groupwise.rl.batch_envs import PARALLEL_MIN_STEPS, BatchEnvs, free_cores, processes_for
from groupwise.rl.policy import RandomPolicy
from groupwise.rl.rollout import sample_episodes_for_windows, sample_trajectories


def hopper() -> gym.Env:
    return make_env("Hopper")


def falling_hopper() -> gym.Env:
    return gym.make("Hopper-v5")  # terminates when it falls: episodes of their own lengths


def _same(first, second) -> None:
    assert len(first) == len(second)
    for a, b in zip(first, second, strict=True):
        assert a.reset_seed == b.reset_seed and a.episode == b.episode
        for name in ("obs", "acts", "actions", "true_rewards"):
            assert getattr(a, name).tobytes() == getattr(b, name).tobytes(), name
        assert a.snapshots.keys() == b.snapshots.keys()
        for step, state in a.snapshots.items():
            assert state.tobytes() == b.snapshots[step].tobytes()
        assert np.array_equal(a.episode_score, b.episode_score, equal_nan=True)


def test_episodes_and_the_generator_are_the_same_whatever_the_processes():
    policy = RandomPolicy(hopper().action_space)
    runs = []
    for processes in (1, 2, 3):
        rng = np.random.default_rng(7)
        episodes = sample_episodes_for_windows(
            hopper, policy, 20, 30, rng, 0.25, max_steps=90, snapshot_offsets=(0, 15),
            processes=processes,
        )  # fmt: skip
        runs.append((episodes, rng.random()))
    assert any(t.snapshots for t in runs[0][0])
    for episodes, draw in runs[1:]:
        _same(runs[0][0], episodes)
        assert draw == runs[0][1]  # the random draws all stayed in this process


def test_episodes_that_end_on_their_own_are_the_same_across_processes():
    policy = RandomPolicy(falling_hopper().action_space)
    alone = sample_trajectories(falling_hopper, policy, 7, np.random.default_rng(3), 0.5)
    spread = sample_trajectories(
        falling_hopper, policy, 7, np.random.default_rng(3), 0.5, processes=2
    )
    assert len({len(t) for t in alone}) > 1
    _same(alone, spread)


def test_a_pool_is_the_same_whatever_the_processes():
    pools = []
    for processes in (1, 2):
        rng = np.random.default_rng(0)
        ensemble = RewardEnsemble.for_env(hopper, RewardConfig(), rng)
        pool = sample_pool(
            hopper, RandomPolicy(hopper().action_space), 12, 40, rng, oversample=2.0,
            exploration_fraction=0.25, ensemble=ensemble, processes=processes,
        )  # fmt: skip
        pools.append((pool, rng.random()))
    (one, draw), (two, again) = pools
    assert draw == again
    assert [f.key for f in one.fragments] == [f.key for f in two.fragments]
    assert one.predicted_returns.tobytes() == two.predicted_returns.tobytes()
    assert one.step_variance is not None and two.step_variance is not None
    assert one.step_variance.tobytes() == two.step_variance.tobytes()
    _same(one.episodes, two.episodes)


def test_a_factory_that_does_not_pickle_steps_every_env_here():
    lock = threading.Lock()  # cloudpickle refuses a lock in the closure

    def make() -> gym.Env:
        with lock:
            return make_env("GridWorld")

    with BatchEnvs(make, 4, processes=2) as envs:
        assert envs.processes == 1 and len(envs.local) == 4


def test_a_helper_that_fails_raises_here():
    parent = os.getpid()

    def make() -> gym.Env:
        if os.getpid() != parent:
            raise RuntimeError("no env in the helper")
        return make_env("GridWorld")

    with pytest.raises(RuntimeError, match="no env in the helper"), BatchEnvs(make, 4, 2) as envs:
        assert envs.processes == 2
        envs.reset([0, 1, 2, 3])


def test_large_batches_use_the_free_cores_and_small_ones_one(monkeypatch):
    from groupwise.rl import batch_envs

    cores = len(os.sched_getaffinity(0))
    readings = iter([])

    def cpu_times():
        return next(readings)

    monkeypatch.setattr(batch_envs, "_cpu_times", cpu_times)
    idle = [0, 0] * cores, [0, 100] * cores  # every core idle in between
    readings = iter(idle * 2)
    assert processes_for(4, 10, None) == 1  # small: no reading taken
    assert processes_for(400, 1000, None) == min(cores, 400) == free_cores(0.0)
    readings = iter([[0, 0] * cores, [95, 5] * cores])  # all busy
    assert processes_for(400, 1000, None) == 1
    monkeypatch.setattr(batch_envs, "_cpu_times", lambda: None)  # no /proc/stat
    monkeypatch.setattr(os, "getloadavg", lambda: (1.0, 1.0, 1.0))  # this process alone
    assert free_cores(0.0) == cores
    monkeypatch.setattr(os, "getloadavg", lambda: (1.0 + 2 * cores, 0.0, 0.0))  # all busy
    assert free_cores(0.0) == 1


def test_idle_cores_sums_each_cores_idle_share():
    from groupwise.rl.batch_envs import idle_cores

    # core 0: 30 busy, 70 idle jiffies in between; core 1: all idle; core 2: no time passed
    assert idle_cores([10, 20, 0, 0, 5, 5], [40, 90, 0, 50, 5, 5]) == pytest.approx(2.7)


def test_the_free_cores_fall_when_a_core_is_kept_busy():
    import subprocess
    import sys

    if len(os.sched_getaffinity(0)) < 2:
        pytest.skip("one core")
    spinner = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    try:
        import time

        time.sleep(0.5)
        assert free_cores(0.5) <= len(os.sched_getaffinity(0)) - 1
    finally:
        spinner.kill()
        spinner.wait()


def test_the_processes_asked_for_are_kept_at_one_per_env():
    assert processes_for(3, PARALLEL_MIN_STEPS, 8) == 3  # asked for: at most one per env
    with pytest.raises(ValueError):
        processes_for(4, 10, 0)
