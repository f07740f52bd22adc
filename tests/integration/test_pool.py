"""Pool preparation end to end: clips in the store, tree and index on disk, reproducible."""

import dataclasses
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from groupwise.behaviour import from_json
from groupwise.clips.store import ClipStore, is_valid_id
from groupwise.clips.video import probe, read_frames
from groupwise.envs import RenderingUnavailableError, make_env, rendering
from groupwise.pool.publish import PreparedPool, PublishConfig, load_fragments, prepare_pool
from groupwise.rl.policy_files import load_policy

GRID = PublishConfig(env="GridWorld", width=64, height=64, workers=2, clips="eager")
GRID_SAMPLING = {"size": 20, "length": 30}
FILES = {
    "pool.json",
    "behaviours.json",
    "behaviours.npz",
    "episodes.npz",
    "distances.npy",
    "tree.json",
    "candidates.json",
    "medoids.json",
    "timings.json",
}


@pytest.fixture(autouse=True)
def _in_temporary_directory(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)  # MuJoCo may write MUJOCO_LOG.TXT into the working directory


@pytest.fixture(scope="module")
def grid_pool(tmp_path_factory: pytest.TempPathFactory) -> PreparedPool:
    out = tmp_path_factory.mktemp("grid")
    policy = load_policy("random", "GridWorld")
    return prepare_pool(
        GRID,
        policy,
        np.random.default_rng(5),
        out,
        **GRID_SAMPLING,
        metadata={"seed": 5},
        show_progress=False,
    )


def test_gridworld_pool_writes_every_file(grid_pool: PreparedPool) -> None:
    out = grid_pool.directory
    assert FILES <= {p.name for p in out.iterdir()}
    manifest = json.loads((out / "pool.json").read_text())
    assert manifest["behaviours"] == 20 and manifest["metadata"] == {"seed": 5}
    store = ClipStore(out / manifest["store"])
    index = json.loads((out / "behaviours.json").read_text())["behaviours"]
    assert [b["id"] for b in index] == [f"b{i}" for i in range(20)]
    for entry, fragment in zip(index, grid_pool.fragments, strict=True):
        assert (entry["episode"], entry["start"]) == (fragment.episode, fragment.start)
        assert entry["true_return"] == pytest.approx(fragment.true_return)
        assert store.path(entry["clip"]).suffix == ".mp4"
        assert store.path(entry["poster"]).suffix == ".jpg"
    timings = json.loads((out / "timings.json").read_text())
    assert timings["total_s"] > 0 and timings["frames"] == 600
    # GridWorld runs at 30 steps a second: a frame per step, 1 s of real time
    assert (manifest["length"], manifest["fps"]) == (30, 30.0)
    clip = manifest["clip"]
    assert (clip["steps"], clip["stride"], clip["frames"]) == (30, 1, 30)
    assert (clip["fps"], clip["seconds"], clip["speed"]) == (30.0, 1.0, 1.0)
    assert manifest["frame_size"] == [64, 64]
    # the config as before issue 19: how the pool was sampled, then how it was published
    assert list(manifest["config"]) == [
        "env", "size", "length", "oversample", "exploration_fraction", "width", "height",
        "video", "tree", "candidate_levels", "max_group", "medoids", "workers", "clips",
    ]  # fmt: skip
    sampled = {k: manifest["config"][k] for k in ("size", "length", "oversample")}
    assert sampled == {"size": 20, "length": 30, "oversample": 1.0}


def test_every_clip_has_l_frames_of_h264(grid_pool: PreparedPool) -> None:
    for clip in set(grid_pool.clips):
        info = probe(grid_pool.store.path(clip))
        assert (info.frames, info.codec, info.pix_fmt) == (30, "h264", "yuv420p")
        assert (info.width, info.height) == (64, 64)


def test_tree_leaves_carry_clip_and_poster_ids(grid_pool: PreparedPool) -> None:
    data = json.loads((grid_pool.directory / "tree.json").read_text())
    tree = from_json(data)
    assert sorted(tree.leaf_order) == list(range(20))
    leaves = []
    stack = [data["root"]]
    while stack:
        node = stack.pop()
        stack.extend(node["children"])
        if node["kind"] == "leaf":
            leaves.append(node)
    assert len(leaves) == 20
    for leaf in leaves:
        i = leaf["behaviour"]
        assert leaf["extra"] == {"clip": grid_pool.clips[i], "poster": grid_pool.posters[i]}
        assert is_valid_id(leaf["extra"]["clip"])
    candidates = json.loads((grid_pool.directory / "candidates.json").read_text())["candidates"]
    assert all(2 <= c["size"] <= 8 and set(c["medoids"]) <= set(c["leaves"]) for c in candidates)


def test_arrays_round_trip(grid_pool: PreparedPool) -> None:
    fragments = load_fragments(grid_pool.directory)
    assert len(fragments) == 20
    for loaded, original in zip(fragments, grid_pool.fragments, strict=True):
        np.testing.assert_array_equal(loaded.obs, original.obs)
        assert loaded.key == original.key
    distances = np.load(grid_pool.directory / "distances.npy")
    np.testing.assert_array_equal(distances, grid_pool.distances)


def test_same_seed_gives_byte_identical_clips_in_process_too(
    grid_pool: PreparedPool, tmp_path: Path
) -> None:
    # rendered in this process instead of two workers: same ids, i.e. the same bytes
    again = prepare_pool(
        dataclasses.replace(GRID, workers=0),
        load_policy("random", "GridWorld"),
        np.random.default_rng(5),
        tmp_path,
        **GRID_SAMPLING,
        show_progress=False,
    )
    assert again.clips == grid_pool.clips and again.posters == grid_pool.posters
    np.testing.assert_array_equal(again.distances, grid_pool.distances)


def test_hopper_clips_show_the_window(tmp_path: Path) -> None:
    cfg = PublishConfig(env="Hopper", width=96, height=96, workers=2, clips="eager")
    pool = prepare_pool(
        cfg,
        load_policy("random", "Hopper"),
        np.random.default_rng(0),
        tmp_path,
        size=6,
        length=20,
        show_progress=False,
    )
    assert len(set(pool.clips)) == 6
    # real speed: a frame every 4th step of 0.008 s, 31.25 frames/s, 20 steps = 0.16 s
    assert (pool.timing.stride, pool.timing.frames) == (4, 5)
    clip = json.loads((tmp_path / "pool.json").read_text())["clip"]
    assert (clip["steps"], clip["fps"], clip["seconds"], clip["speed"]) == (20, 31.25, 0.16, 1.0)
    assert probe(pool.store.path(pool.clips[2])).fps == 31.25
    assert pool.timings.frames == 6 * 5
    fragment = pool.fragments[2]
    frames = read_frames(pool.store.path(pool.clips[2]))
    assert frames.shape == (5, 96, 96, 3)
    assert not any(rendering.frame_is_blank(f) for f in frames)
    assert np.abs(frames[0].astype(int) - frames[-1]).mean() > 0.5  # it moves
    # frame 0 is the state the window's first observation came from
    actions = np.load(tmp_path / "episodes.npz")["actions"][fragment.episode]
    env = make_env("Hopper", render_mode="rgb_array", width=96, height=96)
    obs, _ = env.reset(seed=fragment.reset_seed)
    for action in actions[: fragment.start]:
        obs = env.step(action)[0]
    np.testing.assert_allclose(obs, fragment.obs[0], rtol=1e-5, atol=1e-5)
    direct = np.asarray(env.render(), dtype=int)
    env.close()
    assert np.abs(frames[0] - direct).mean() < 6


def test_missing_renderer_names_the_system_package(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("MUJOCO_GL", raising=False)
    monkeypatch.delenv("PYOPENGL_PLATFORM", raising=False)
    monkeypatch.setattr(rendering, "_backend_works", lambda backend: False)
    cfg = PublishConfig(env="Hopper", workers=0, clips="eager")
    with pytest.raises(RenderingUnavailableError, match="apt-get install libegl1"):
        prepare_pool(
            cfg,
            load_policy("random", "Hopper"),
            np.random.default_rng(0),
            tmp_path,
            size=2,
            length=30,
        )


def test_checkpoint_policy_samples_a_pool(tmp_path: Path) -> None:
    from groupwise.config import PPOConfig
    from groupwise.rl.ppo import PPOAgent

    checkpoint = tmp_path / "run" / "checkpoints" / "round-0000"
    agent = PPOAgent(lambda: make_env("GridWorld"), PPOConfig(n_envs=1, tensorboard=False), 0)
    agent.save(checkpoint)
    agent.close()
    policy = load_policy(str(checkpoint), "GridWorld")
    cfg = PublishConfig(env="GridWorld", width=32, height=32, workers=0, clips="eager")
    pool = prepare_pool(cfg, policy, np.random.default_rng(0), tmp_path / "pool", size=4, length=30)
    assert len(pool.clips) == 4


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "groupwise.cli", *args],
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, "PYTHONWARNINGS": "ignore"},
    )


def test_cli_prepares_a_pool(tmp_path: Path) -> None:
    result = _cli(
        "pool", "--env", "GridWorld", "--n", "6", "--size", "32", "--workers", "0",
        "--seed", "2", "--out", str(tmp_path), "-q",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "6 behaviours" in result.stdout
    assert (tmp_path / "tree.json").is_file()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--env", "NoSuchEnv"], "NoSuchEnv"),
        (["--env", "GridWorld", "--policy", "/no/such/checkpoint"], "checkpoint"),
        (["--env", "GridWorld", "--size", "33"], "even"),
        (["--env", "GridWorld", "--exploration", "1"], "exploration"),
    ],
)
def test_cli_errors_are_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], message: str
) -> None:
    from groupwise.cli import main

    code = main(["pool", *args, "--out", str(tmp_path / "out"), "-q"])
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err and "Traceback" not in err
