"""Preparing a round's behaviour pool: everything the interface needs, written to a directory.

One function, `prepare_pool`, readable top to bottom:

1. **sample** whole episodes from a policy (`rl.rollout.sample_trajectories`), enough that
   tiling them gives `oversample` × `size` windows;
2. **cut** them into non-overlapping windows of L steps (`clips.fragments.tile_fragments`) and
   keep `size` of them: the most uncertain when an `uncertainty` function is given (SPEC §3.2),
   otherwise a uniformly random subset;
3. **clips**: hand the windows to the render workers (`clips.render`), which replay each
   episode from its reset seed, render exactly the kept windows, and encode each as an MP4 and
   a poster into the clip store, while the parent computes
4. **features**, **DTW** distances, the **tree** and its group candidates (`behaviour`);
5. **write** the directory (below) and return a `PreparedPool` with per-phase timings.

The worker processes start (and build their rendering envs) while the parent samples, and
render while the parent computes distances, so the phases overlap: the timings are each
phase's own wall time, and ``total_s`` is the wall time of the whole call.

Directory layout (``format: groupwise.pool/1``)::

    pool.json         manifest: config, metadata (policy, seed), env, counts, file names
    behaviours.json   per behaviour: id ("b<i>", as in the tree), index, key, episode, start,
                      reset_seed, true_return, clip id, poster id
    behaviours.npz    obs (N, L, obs_dim), acts (N, L, act_dim), actions (N, L, *act_shape)
                      raw, true_rewards (N, L), episode, start, reset_seed (N,)
    episodes.npz      episode, reset_seed (E,), actions (E, T, *act_shape): enough to replay
                      (re-render) any window of the sampled episodes
    distances.npy     condensed DTW distances (N (N - 1) / 2,)
    tree.json         `behaviour.to_json` with leaf extras {"clip": id, "poster": id}
    candidates.json   group candidates: node id, level, size, leaves, medoids
    medoids.json      node id → up to `medoids` representative behaviours, for every inner node
    timings.json      `PoolTimings`
    clips/            the clip store (unless another store is passed in)
"""

import dataclasses
import json
import logging
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from groupwise.behaviour import (
    BehaviourTree,
    TreeConfig,
    TreeNode,
    build_tree,
    dtw_matrix,
    group_candidates,
    medoids,
    pool_features,
    to_json,
)
from groupwise.fragments import Fragment, Trajectory, most_uncertain, tile_fragments
from groupwise.clips.render import RenderPool, plan_jobs
from groupwise.clips.replay import FrameSettings, make_render_env
from groupwise.clips.store import ClipStore
from groupwise.clips.video import VideoConfig
from groupwise.envs import horizon, make_env
from groupwise.rl.policy import Policy, RandomPolicy
from groupwise.rl.rollout import sample_trajectories
from groupwise.types import FloatArray, IntArray

logger = logging.getLogger(__name__)

FORMAT = "groupwise.pool/1"
STORE_DIR = "clips"
Uncertainty = Callable[[FloatArray, FloatArray], FloatArray]
"""(obs (N, L, obs_dim), acts (N, L, act_dim)) -> (N,) score; higher is kept first."""


@dataclass(frozen=True)
class PoolConfig:
    """What pool to prepare and how."""

    env: str = "Hopper"
    """Short env name (`groupwise.envs.ENVS`) or Gymnasium id with a fixed horizon."""
    size: int = 200
    """Behaviours in the pool, N (SPEC §1: 100-200; the paper advises < 200)."""
    length: int = 30
    """Steps per behaviour, L; each clip has exactly L frames."""
    oversample: float = 1.0
    """Sample episodes for this many times `size` windows. 1 is enough for a random subset;
    raise it (the loop uses 2) when an uncertainty function chooses the windows."""
    exploration_fraction: float = 0.0
    """Share of steps taken by random actions while sampling (SPEC §3.1)."""
    width: int = 240
    """Frame width in pixels (even)."""
    height: int = 240
    """Frame height in pixels (even)."""
    video: VideoConfig = field(default_factory=VideoConfig)
    """Clip and poster encoding."""
    tree: TreeConfig = field(default_factory=TreeConfig)
    """How the behaviour tree is cut."""
    dtw_window: int | None = None
    """Sakoe–Chiba radius of the DTW distances in steps (None: unconstrained)."""
    candidate_levels: tuple[int, ...] = (1, 2)
    """Tree levels whose nodes are group candidates (SPEC §4)."""
    max_group: int = 8
    """Largest group candidate (smallest is 2)."""
    medoids: int = 3
    """Representative clips kept per inner tree node (hover previews, SPEC §9)."""
    workers: int = 2
    """Render worker processes (0: render in this process)."""

    def __post_init__(self) -> None:
        if self.size < 1 or self.length < 1:
            raise ValueError(f"size and length must be >= 1, got {self.size}, {self.length}")
        if self.oversample < 1.0:
            raise ValueError(f"oversample must be >= 1, got {self.oversample}")
        if self.width < 2 or self.height < 2 or self.width % 2 or self.height % 2:
            raise ValueError(f"frame size must be even, got {self.width}×{self.height}")
        if self.workers < 0:
            raise ValueError(f"workers must be >= 0, got {self.workers}")
        if not 0.0 <= self.exploration_fraction < 1.0:
            raise ValueError(f"exploration must be in [0, 1), got {self.exploration_fraction}")


@dataclass(frozen=True)
class PoolTimings:
    """Seconds per phase. Wall times of the parent, except the worker sums (see below)."""

    sample_s: float  # sampling episodes and cutting windows
    clips_s: float  # from handing jobs to the workers until the last clip is stored
    features_s: float  # standardised step features (overlaps clips_s)
    dtw_s: float  # DTW distance matrix (overlaps clips_s)
    tree_s: float  # tree, group candidates, medoids (overlaps clips_s)
    write_s: float  # writing the directory
    total_s: float  # the whole call, wall time
    render_s: float  # worker-seconds in env.render(), summed over workers
    encode_s: float  # worker-seconds handing frames to ffmpeg, posters, storing, summed
    ffmpeg_cpu_s: float  # CPU seconds of the ffmpeg processes (they run beside the workers)
    replay_s: float  # worker-seconds stepping and checking replays, summed over workers
    workers: int
    behaviours: int
    frames: int  # frames rendered (N × L)


@dataclass(frozen=True)
class PreparedPool:
    """A prepared pool (also written to `directory`, see the module docstring)."""

    directory: Path
    store: ClipStore
    fragments: tuple[Fragment, ...]  # (N,) in behaviour-index order
    clips: tuple[str, ...]  # (N,) clip-store id of each behaviour's MP4
    posters: tuple[str, ...]  # (N,) clip-store id of each behaviour's poster
    distances: FloatArray  # (N (N - 1) / 2,) condensed DTW distances
    tree: BehaviourTree
    candidates: tuple[TreeNode, ...]
    timings: PoolTimings


def load_policy(spec: str, env: str) -> Policy:
    """ "random", or a checkpoint directory (``policy.zip`` + ``vecnormalize.npz``, as
    written by `groupwise train` under ``<out>/checkpoints/round-NNNN/``).

    A checkpoint is loaded with the PPO settings of its run's ``config.json`` when that is
    found two levels up, the defaults otherwise; it acts stochastically.

    Raises:
        FileNotFoundError: the directory has no ``policy.zip``.
        ValueError: unknown env, or the checkpoint's spaces do not match the env's.
    """
    if spec == "random":
        probe = make_env(env)
        try:
            return RandomPolicy(probe.action_space)
        finally:
            probe.close()
    from groupwise.config import PPOConfig, RunConfig
    from groupwise.rl.ppo import POLICY_FILE, PPOAgent

    directory = Path(spec)
    if not (directory / POLICY_FILE).is_file():
        raise FileNotFoundError(f"{directory} is not a checkpoint directory (no {POLICY_FILE})")
    config_file = directory.parent.parent / "config.json"
    ppo = RunConfig.load(config_file).ppo if config_file.is_file() else PPOConfig()
    ppo = dataclasses.replace(ppo, n_envs=1, tensorboard=False)
    agent = PPOAgent(lambda: make_env(env), ppo, seed=0)
    agent.load(directory)
    return agent.policy(deterministic=False)


def prepare_pool(
    cfg: PoolConfig,
    policy: Policy,
    rng: np.random.Generator,
    out: Path,
    *,
    store: ClipStore | None = None,
    render_pool: RenderPool | None = None,
    uncertainty: Uncertainty | None = None,
    metadata: Mapping[str, Any] | None = None,
    show_progress: bool = True,
) -> PreparedPool:
    """Sample, cut, render, encode, cluster and write one pool (module docstring).

    `store` defaults to ``out/clips``; `render_pool` (reused across rounds by a long-lived
    caller) defaults to a fresh one with `cfg.workers` workers, closed on return.
    `metadata` (e.g. policy and seed) is written into ``pool.json``.

    Raises:
        RenderingUnavailableError: the env cannot render offscreen (names the packages).
        ReplayMismatchError: the env does not replay deterministically.
        ValueError: unknown env, or an env without a fixed horizon of at least L steps.
    """
    started = time.perf_counter()
    out.mkdir(parents=True, exist_ok=True)
    store = store or ClipStore(out / STORE_DIR)
    settings = FrameSettings(cfg.env, cfg.width, cfg.height, cfg.video)
    _check_rendering(settings)
    own_pool = render_pool is None
    workers = render_pool or RenderPool(cfg.workers)
    try:
        workers.warm_up(settings)
        tick = time.perf_counter()
        trajectories, fragments = _sample(cfg, policy, rng, uncertainty)
        sample_s = time.perf_counter() - tick

        tick = time.perf_counter()
        jobs = plan_jobs(trajectories, fragments, settings, workers.workers)
        pending = workers.start(jobs, store)
        mark = time.perf_counter()
        features = pool_features(fragments)
        features_s = time.perf_counter() - mark
        mark = time.perf_counter()
        distances = dtw_matrix(features, window=cfg.dtw_window)
        dtw_s = time.perf_counter() - mark
        mark = time.perf_counter()
        tree = build_tree(distances, cfg.tree)
        candidates = group_candidates(tree, cfg.candidate_levels, 2, cfg.max_group)
        representatives = {
            node.id: medoids(node, distances, cfg.medoids)
            for node in tree.nodes()
            if node.kind != "leaf"
        }
        tree_s = time.perf_counter() - mark
        reports = pending.wait(show_progress)
        clips_s = time.perf_counter() - tick
    finally:
        if own_pool:
            workers.close()

    rendered = {(c.episode, c.start): c for report in reports for c in report.clips}
    clips = tuple(rendered[(f.episode, f.start)].clip for f in fragments)
    posters = tuple(rendered[(f.episode, f.start)].poster for f in fragments)

    tick = time.perf_counter()
    partial = PoolTimings(
        sample_s=sample_s,
        clips_s=clips_s,
        features_s=features_s,
        dtw_s=dtw_s,
        tree_s=tree_s,
        write_s=0.0,
        total_s=0.0,
        render_s=sum(r.render_s for r in reports),
        encode_s=sum(r.encode_s for r in reports),
        ffmpeg_cpu_s=sum(r.ffmpeg_cpu_s for r in reports),
        replay_s=sum(r.replay_s for r in reports),
        workers=workers.workers,
        behaviours=len(fragments),
        frames=len(fragments) * cfg.length,
    )
    prepared = PreparedPool(
        directory=out,
        store=store,
        fragments=tuple(fragments),
        clips=clips,
        posters=posters,
        distances=distances,
        tree=tree,
        candidates=tuple(candidates),
        timings=partial,
    )
    _write(prepared, trajectories, representatives, cfg, metadata or {})
    write_s = time.perf_counter() - tick
    timings = dataclasses.replace(partial, write_s=write_s, total_s=time.perf_counter() - started)
    _write_json(out / "timings.json", dataclasses.asdict(timings))
    logger.info(
        "pool of %d behaviours in %.1f s (sample %.1f, clips %.1f, write %.1f)",
        len(fragments),
        timings.total_s,
        sample_s,
        clips_s,
        write_s,
    )
    return dataclasses.replace(prepared, timings=timings)


def _check_rendering(settings: FrameSettings) -> None:
    # Renders one frame here, before any worker starts: a missing GL library fails now with
    # the envs package's message, and the chosen MUJOCO_GL is inherited by the workers.
    env = make_render_env(settings)
    try:
        env.reset(seed=0)
        env.render()
    finally:
        env.close()


def _sample(
    cfg: PoolConfig,
    policy: Policy,
    rng: np.random.Generator,
    uncertainty: Uncertainty | None,
) -> tuple[list[Trajectory], list[Fragment]]:
    steps = horizon(cfg.env)
    if steps is None or steps < cfg.length:
        raise ValueError(
            f"env {cfg.env} needs a fixed horizon of at least {cfg.length} steps, has {steps}"
        )
    episodes = max(1, math.ceil(cfg.size * cfg.oversample / (steps // cfg.length)))
    trajectories = sample_trajectories(
        lambda: make_env(cfg.env), policy, episodes, rng, cfg.exploration_fraction
    )
    windows = tile_fragments(trajectories, cfg.length)
    keep: IntArray
    if len(windows) <= cfg.size:
        keep = np.arange(len(windows))
    elif uncertainty is not None:
        obs = np.stack([w.obs for w in windows])
        acts = np.stack([w.acts for w in windows])
        keep = most_uncertain(uncertainty(obs, acts), cfg.size)
    else:
        keep = np.sort(rng.choice(len(windows), size=cfg.size, replace=False))
    return trajectories, [windows[i] for i in keep]


def _write(
    pool: PreparedPool,
    trajectories: list[Trajectory],
    representatives: Mapping[str, tuple[int, ...]],
    cfg: PoolConfig,
    metadata: Mapping[str, Any],
) -> None:
    out, fragments = pool.directory, pool.fragments
    by_episode = {t.episode: t for t in trajectories}
    raw = np.stack([by_episode[f.episode].actions[f.start : f.start + f.length] for f in fragments])
    np.savez(
        out / "behaviours.npz",
        obs=np.stack([f.obs for f in fragments]),
        acts=np.stack([f.acts for f in fragments]),
        actions=raw,
        true_rewards=np.stack([f.true_rewards for f in fragments]),
        episode=np.array([f.episode for f in fragments]),
        start=np.array([f.start for f in fragments]),
        reset_seed=np.array([f.reset_seed for f in fragments]),
    )
    np.savez(
        out / "episodes.npz",
        episode=np.array([t.episode for t in trajectories]),
        reset_seed=np.array([t.reset_seed for t in trajectories]),
        actions=np.stack([np.asarray(t.actions) for t in trajectories]),
    )
    np.save(out / "distances.npy", pool.distances)
    behaviours = [
        {
            "id": f"b{i}",
            "index": i,
            "key": f.key,
            "episode": f.episode,
            "start": f.start,
            "reset_seed": f.reset_seed,
            "true_return": f.true_return,
            "clip": pool.clips[i],
            "poster": pool.posters[i],
        }
        for i, f in enumerate(fragments)
    ]
    _write_json(out / "behaviours.json", {"format": FORMAT, "behaviours": behaviours})
    extra = {i: {"clip": pool.clips[i], "poster": pool.posters[i]} for i in range(len(fragments))}
    _write_json(out / "tree.json", to_json(pool.tree, leaf_extra=extra))
    candidates = [
        {
            "id": node.id,
            "level": node.level,
            "size": node.size,
            "leaves": list(node.leaves),
            "medoids": list(representatives[node.id]),
        }
        for node in pool.candidates
    ]
    _write_json(out / "candidates.json", {"format": FORMAT, "candidates": candidates})
    _write_json(out / "medoids.json", {k: list(v) for k, v in representatives.items()})
    manifest = {
        "format": FORMAT,
        "env": cfg.env,
        "behaviours": len(fragments),
        "episodes": len(trajectories),
        "length": cfg.length,
        "fps": cfg.video.fps,
        "frame_size": [cfg.width, cfg.height],
        "store": _relative(pool.store.root, out),
        "config": dataclasses.asdict(cfg),
        "metadata": dict(metadata),
    }
    _write_json(out / "pool.json", manifest)


def load_fragments(directory: Path) -> tuple[Fragment, ...]:
    """The fragments of a pool written by `prepare_pool`, in behaviour-index order."""
    with np.load(directory / "behaviours.npz") as data:
        return tuple(
            Fragment(
                obs=data["obs"][i],
                acts=data["acts"][i],
                true_rewards=data["true_rewards"][i],
                episode=int(data["episode"][i]),
                start=int(data["start"][i]),
                reset_seed=int(data["reset_seed"][i]),
            )
            for i in range(len(data["start"]))
        )


def _relative(path: Path, base: Path) -> str:
    try:
        return str(path.resolve().relative_to(base.resolve()))
    except ValueError:
        return str(path.resolve())


def _write_json(path: Path, data: Any) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(data, indent=1))
    tmp.replace(path)
