"""Publishing a round's behaviour pool: everything the interface needs, written to a directory.

`publish_pool` takes a sampled pool (`loop.sample_pool` in the app, `sampling.sample_pool`
from a bare policy in `prepare_pool`) and, readable top to bottom:

1. **clips**: hands the windows to the render workers (`clips.render`), which replay each
   episode from its reset seed, render exactly the pool's windows (at real speed, a frame
   every k-th step: `clips.timing`), and encode each as an MP4 and a poster into the clip
   store, while the parent computes
2. the pool's **DTW** distances (`BehaviourPool.distances`), the **tree**, its group
   candidates and medoids (`behaviour`);
3. **writes** the directory (`pool_files`) and returns a `PreparedPool` with per-phase
   timings.

The worker processes start (and build their rendering envs) before the parent computes
distances, and render meanwhile, so the phases overlap: the timings are each phase's own
wall time, and ``total_s`` is the wall time of the whole call.
"""

import dataclasses
import logging
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from groupwise.behaviour import (
    TreeConfig,
    group_candidates,
    medoids,
)
from groupwise.clips.render import RenderPool, plan_jobs
from groupwise.clips.replay import FrameSettings, make_render_env
from groupwise.clips.store import ClipStore
from groupwise.clips.timing import clip_timing, step_seconds
from groupwise.clips.video import VideoConfig
from groupwise.envs import make_env
from groupwise.pool.behaviours import BehaviourPool
from groupwise.pool.files import (
    FORMAT,
    PoolTimings,
    PreparedPool,
    load_fragments,
    write_json,
    write_pool,
)
from groupwise.pool.sampling import sample_pool
from groupwise.preferences.judgement import MAX_GROUP
from groupwise.rl.policy import Policy, RandomPolicy

logger = logging.getLogger(__name__)

STORE_DIR = "clips"
__all__ = ["FORMAT", "PoolTimings", "PreparedPool", "load_fragments"]  # re-exported


@dataclass(frozen=True)
class PoolConfig:
    """What pool to prepare and how."""

    env: str = "Hopper"
    """Short env name (`groupwise.envs.ENVS`) or Gymnasium id with a fixed horizon."""
    size: int = 200
    """Behaviours in the pool, N (SPEC §1: 100-200; the paper advises < 200)."""
    length: int = 30
    """Steps per behaviour, L; each clip shows them at real speed, a frame every k-th step
    (`clips.timing`; the app's default L is the env's clip duration, `env_clip_timing`)."""
    oversample: float = 1.0
    """Sample episodes for this many times `size` windows, of which `size` are kept."""
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
    candidate_levels: tuple[int, ...] = (1, 2)
    """Tree levels whose nodes are group candidates (SPEC §4)."""
    max_group: int = MAX_GROUP
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
    metadata: Mapping[str, Any] | None = None,
    show_progress: bool = True,
) -> PreparedPool:
    """Sample `cfg.size` behaviours of `policy` (a random subset of `cfg.oversample` ×
    `cfg.size` windows) and publish them into `out` (`publish_pool`)."""
    tick = time.perf_counter()
    pool = sample_pool(
        lambda: make_env(cfg.env),
        policy,
        cfg.size,
        cfg.length,
        rng,
        exploration_fraction=cfg.exploration_fraction,
        oversample=cfg.oversample,
    )
    sample_s = time.perf_counter() - tick
    return publish_pool(
        cfg,
        pool,
        out,
        store=store,
        render_pool=render_pool,
        metadata=metadata,
        show_progress=show_progress,
        sample_s=sample_s,
    )


def publish_pool(
    cfg: PoolConfig,
    pool: BehaviourPool,
    out: Path,
    *,
    store: ClipStore | None = None,
    render_pool: RenderPool | None = None,
    metadata: Mapping[str, Any] | None = None,
    show_progress: bool = True,
    sample_s: float = 0.0,
) -> PreparedPool:
    """Render, encode, cluster and write a sampled pool (module docstring).

    `pool.episodes` must hold the episodes its fragments were cut from (they are replayed
    into clips). `store` defaults to ``out/clips``; `render_pool` (reused across rounds by
    a long-lived caller) defaults to a fresh one with `cfg.workers` workers, closed on
    return. `metadata` (e.g. policy and seed) is written into ``pool.json``; `sample_s`,
    the time it took to sample the pool, into the timings.

    Raises:
        RenderingUnavailableError: the env cannot render offscreen (names the packages).
        ReplayMismatchError: the env does not replay deterministically.
        ValueError: unknown env, or a pool without its episodes.
    """
    started = time.perf_counter() - sample_s
    if not pool.episodes or not pool.fragments:
        raise ValueError("the pool carries no behaviours, or no episodes to replay into clips")
    out.mkdir(parents=True, exist_ok=True)
    store = store or ClipStore(out / STORE_DIR)
    settings = FrameSettings(cfg.env, cfg.width, cfg.height, cfg.video)
    timing = clip_timing(_check_rendering(settings), steps=pool.fragments[0].length)
    own_pool = render_pool is None
    workers = render_pool or RenderPool(cfg.workers)
    trajectories, fragments = list(pool.episodes), list(pool.fragments)
    try:
        workers.warm_up(settings)
        tick = time.perf_counter()
        jobs = plan_jobs(
            trajectories,
            fragments,
            settings,
            workers.workers,
            stride=timing.stride,
            fps=timing.fps,
        )
        pending = workers.start(jobs, store)
        mark = time.perf_counter()
        distances = pool.distances
        dtw_s = time.perf_counter() - mark
        mark = time.perf_counter()
        tree = pool.tree(cfg.tree)
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
        features_s=0.0,
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
        frames=len(fragments) * timing.frames,
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
        timing=timing,
    )
    write_pool(prepared, pool, representatives, dataclasses.asdict(cfg), metadata or {})
    write_s = time.perf_counter() - tick
    timings = dataclasses.replace(partial, write_s=write_s, total_s=time.perf_counter() - started)
    write_json(out / "timings.json", dataclasses.asdict(timings))
    logger.info(
        "pool of %d behaviours in %.1f s (sample %.1f, clips %.1f, write %.1f)",
        len(fragments),
        timings.total_s,
        sample_s,
        clips_s,
        write_s,
    )
    return dataclasses.replace(prepared, timings=timings)


def _check_rendering(settings: FrameSettings) -> float:
    """The env's seconds per step (`clips.timing.step_seconds`), after rendering one frame.

    Rendering here, before any worker starts, makes a missing GL library fail now with the
    envs package's message, and the chosen MUJOCO_GL is inherited by the workers."""
    env = make_render_env(settings)
    try:
        env.reset(seed=0)
        env.render()
        return step_seconds(env)
    finally:
        env.close()
