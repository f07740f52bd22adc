"""A recorded dataset as the pool's source (`pool.dataset`, `envs.datasets`; issue 42): its
windows, and clips drawn from physics states rebuilt from the observations."""

import numpy as np
import pytest
from tests.datasets import HOPPER, build_hopper_dataset

from groupwise.clips.env_cache import cached_env
from groupwise.clips.recipe import ClipRecipe, window_frames, window_recipe
from groupwise.clips.replay import FrameSettings
from groupwise.clips.timing import clip_timing, step_seconds
from groupwise.envs import make_env
from groupwise.envs.datasets import (
    DatasetError,
    RecordedStates,
    open_dataset,
    rebuilt_positions,
)
from groupwise.pool.dataset import RecordedEpisodes, recorded_windows
from groupwise.pool.sampling import sample_pool

pytest.importorskip("minari")
pytest.importorskip("jax")  # Minari's DataCollector needs it (groupwise[dev])

X_ERROR_M = 0.0055
"""Hopper-v5: the reset's x noise (±0.005 m) and the integration's drift (docstring of
`envs.datasets`: at most 0.4 mm over 73 steps)."""
FRAME_ERROR = 1.0
"""Mean absolute difference of a rebuilt-state frame from a rerun's, in 8-bit levels: the
floor under the body shifts by the x error (measured: 0.08 at 96 × 96 px, x off by 1.5 mm)."""


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    root = tmp_path_factory.mktemp("minari")
    build_hopper_dataset(root, "test/hopper-random-v0", steps=400)
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("MINARI_DATASETS_PATH", str(root))
        yield root


def test_a_minari_dataset_opens_by_id_and_by_directory(store):
    by_id = open_dataset("minari:test/hopper-random-v0")
    by_dir = open_dataset(str(store / "test" / "hopper-random-v0"))
    assert by_id.env == by_dir.env == HOPPER
    assert by_id.steps == by_dir.steps == 400
    assert [len(e) for e in by_id.episodes] == [len(e) for e in by_dir.episodes]
    with pytest.raises(DatasetError, match=r"not in the local Minari store.*never downloads"):
        open_dataset("minari:mujoco/hopper/expert-v0")
    for outside in (f"minari:../{store.name}/test/hopper-random-v0", f"minari:{store}/test"):
        with pytest.raises(DatasetError, match="not in the local Minari store"):
            open_dataset(outside)  # an id names a dataset of the store, nothing else
    with pytest.raises(DatasetError, match="no such Minari dataset directory"):
        open_dataset(str(store / "nothing-here"))


def test_windows_are_drawn_from_every_episode_and_never_cross_an_end(store):
    dataset = open_dataset("minari:test/hopper-random-v0")
    places = recorded_windows(dataset.episodes, 10, np.random.default_rng(1))
    for episode, start in places:
        assert 0 <= start and start + 10 <= len(dataset.episodes[episode])
    held = sum(len(e) // 10 for e in dataset.episodes)
    assert held - len(dataset.episodes) <= len(places) <= held
    pool = sample_pool(
        lambda: make_env(HOPPER), None, 8, 10, np.random.default_rng(2),
        sources=(RecordedEpisodes("minari:test/hopper-random-v0", HOPPER),),
    )  # fmt: skip
    assert len(pool) == 8
    steps = np.concatenate([e.obs for e in dataset.episodes])
    for fragment in pool.fragments:  # reset_seed: the window's first step in the dataset
        start = fragment.reset_seed
        np.testing.assert_allclose(fragment.obs, steps[start : start + 10], rtol=1e-6)


def test_positions_rebuilt_from_the_observation_follow_a_rerun():
    env = make_env(HOPPER)
    rng = np.random.default_rng(0)
    obs, xs = [env.reset(seed=3)[0]], [env.unwrapped.data.qpos[0]]
    for _ in range(60):
        o, _, terminated, _, _ = env.step(rng.uniform(-1, 1, 3))
        if terminated:
            break
        obs.append(o)
        xs.append(env.unwrapped.data.qpos[0])
    model = env.unwrapped.model
    qpos, _ = rebuilt_positions(np.array(obs), model.nq, model.nv, env.unwrapped.dt)
    np.testing.assert_allclose(qpos[:, 1:], np.array(obs)[:, :5])
    assert np.abs(qpos[:, 0] - np.array(xs)).max() <= X_ERROR_M


def test_a_rebuilt_state_clips_first_frame_is_a_reruns_within_the_documented_error(store):
    """Episode 0 of the dataset is Hopper-v5 reset with seed 0, then its recorded actions:
    rerun them and draw the frame of a window's first step, then draw the same window's clip
    from states rebuilt from the observations alone."""
    dataset = open_dataset("minari:test/hopper-random-v0")
    episode, length = dataset.episodes[0], 8
    pool = sample_pool(
        lambda: make_env(HOPPER), None, 400, length, np.random.default_rng(0),
        sources=(RecordedEpisodes("minari:test/hopper-random-v0", HOPPER),),
    )  # fmt: skip
    fragment = max(  # episode 0's last window: the most steps of drift
        (f for f in pool.fragments if f.reset_seed + length <= len(episode)),
        key=lambda f: f.reset_seed,
    )
    start = fragment.reset_seed
    settings = FrameSettings(HOPPER, 96, 96)
    env = cached_env(settings)
    env.reset(seed=0)
    for t in range(start):
        obs = env.step(episode.actions[t])[0]
        np.testing.assert_allclose(obs, episode.obs[t + 1], atol=1e-9)  # the same episode
    rerun = np.asarray(env.render()).astype(np.float64)
    rerun_x = float(env.unwrapped.data.qpos[0])
    trajectory = next(t for t in pool.episodes if t.episode == fragment.episode)
    assert isinstance(trajectory.snapshots, RecordedStates)
    assert abs(trajectory.snapshots.qpos[0, 0] - rerun_x) <= X_ERROR_M
    timing = clip_timing(step_seconds(make_env(HOPPER)), steps=length)
    recipe = window_recipe(trajectory, fragment, settings, timing)
    recipe = ClipRecipe.from_bytes(recipe.to_bytes())  # as the server reads it back
    first = window_frames(recipe, cached_env(settings))[0].astype(np.float64)
    assert first.shape == rerun.shape
    error = np.abs(first - rerun).mean()
    assert error <= FRAME_ERROR, error
    other = window_frames(recipe, cached_env(settings))[-1].astype(np.float64)
    assert np.abs(other - rerun).mean() > error  # the test can tell frames apart


def test_a_d4rl_style_hdf5_file_with_stored_states_draws_a_reruns_frames(tmp_path):
    """A D4RL-style file: two episodes of Hopper-v5 (reset seeds 0 and 1) with their qpos and
    qvel in ``infos/``: a window's frames are a rerun's, exactly."""
    h5py = pytest.importorskip("h5py")
    settings = FrameSettings(HOPPER, 64, 64)
    env = cached_env(settings)
    rng = np.random.default_rng(5)
    rows: dict[str, list] = {k: [] for k in ("obs", "act", "rew", "end", "qpos", "qvel")}
    frames = []
    for seed in (0, 1):
        obs = env.reset(seed=seed)[0]
        for t in range(30):
            rows["qpos"].append(env.unwrapped.data.qpos.copy())
            rows["qvel"].append(env.unwrapped.data.qvel.copy())
            if seed == 1:
                frames.append(np.asarray(env.render()))
            action = rng.uniform(-1, 1, 3)
            rows["obs"].append(obs)
            rows["act"].append(action)
            obs, reward, terminated, _, _ = env.step(action)
            rows["rew"].append(reward)
            rows["end"].append(terminated or t == 29)
            if terminated:
                break
    path = tmp_path / "hopper.hdf5"
    with h5py.File(path, "w") as f:
        f.attrs["env"] = HOPPER
        f["observations"], f["actions"] = np.array(rows["obs"]), np.array(rows["act"])
        f["rewards"], f["terminals"] = np.array(rows["rew"]), np.array(rows["end"])
        f["infos/qpos"], f["infos/qvel"] = np.array(rows["qpos"]), np.array(rows["qvel"])
    dataset = open_dataset(str(path))
    assert dataset.env == HOPPER and dataset.has_states and len(dataset.episodes) == 2
    first = len(dataset.episodes[0])
    pool = sample_pool(
        lambda: make_env(HOPPER), None, 100, 5, np.random.default_rng(0),
        sources=(RecordedEpisodes(str(path), HOPPER),),
    )  # fmt: skip
    fragment = next(f for f in pool.fragments if f.reset_seed >= first)  # of episode 1
    trajectory = next(t for t in pool.episodes if t.episode == fragment.episode)
    timing = clip_timing(step_seconds(make_env(HOPPER)), steps=5)
    recipe = window_recipe(trajectory, fragment, settings, timing)
    drawn = window_frames(recipe, cached_env(settings))
    start = fragment.reset_seed - first
    np.testing.assert_array_equal(drawn[0], frames[start])


def test_with_an_ensemble_a_dataset_pool_keeps_the_windows_it_is_least_sure_of(store):
    """The source draws 2 N windows uniformly; `sample_pool` keeps the N of them whose
    predicted returns the ensemble's members disagree on most, as for any source."""
    from groupwise.config import RewardConfig
    from groupwise.episodes.fragments import stack_fragments, tile_fragments
    from groupwise.reward import RewardEnsemble

    ensemble = RewardEnsemble.for_env(
        lambda: make_env(HOPPER), RewardConfig(ensemble_size=3), np.random.default_rng(0)
    )
    source = RecordedEpisodes("minari:test/hopper-random-v0", HOPPER)
    args = (lambda: make_env(HOPPER), None, 8, 10)
    pool = sample_pool(
        *args, np.random.default_rng(4), sources=(source,), oversample=2.0, ensemble=ensemble
    )
    drawn = sample_pool(*args, np.random.default_rng(4), sources=(source,), oversample=2.0)
    assert len(drawn.episodes) == 16  # the same draw of 2 N windows (the same stream)
    windows = tile_fragments(drawn.episodes, 10)
    spread = ensemble.returns(*stack_fragments(windows)).var(axis=1)
    wanted = sorted(np.argsort(-spread)[:8])
    assert [f.reset_seed for f in pool.fragments] == [windows[i].reset_seed for i in wanted]
