"""Publishing a round's behaviour pool: everything the interface needs, written to a directory.

`publish_pool` takes a sampled pool (`run.round.begin_round` in the app, `sampling.sample_pool`
from a bare policy in `prepare_pool`) and a `PublishConfig` (what publishing alone needs:
frame size, encoding, tree, candidates, render workers) and, readable top to bottom:

1. **clips**: hands the windows to the render workers (`clips.render`), which replay each
   episode from its reset seed, render exactly the pool's windows (at real speed, a frame
   every k-th step: `clips.timing`), and encode each as an MP4 and a poster into the clip
   store — or, with ``clips="on_demand"``, keep each window's recipe in the store and render
   only its poster (`clips.recipe`; the server renders a clip when the page first asks for
   it, `clips.on_demand`) — while the parent computes
2. the pool's **DTW** distances (`BehaviourPool.distances`), the **tree**, its group
   candidates and medoids (`behaviour`);
3. **writes** the directory (`files`) and returns a `PreparedPool` with per-phase
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
from typing import Any, Literal

import numpy as np

from groupwise.behaviour import (
    TreeConfig,
    group_candidates,
    medoids,
)
from groupwise.behaviour.pool import BehaviourPool
from groupwise.clips.render import RenderPool
from groupwise.clips.render_jobs import ClipJob, PosterJob, plan_jobs, plan_poster_jobs
from groupwise.clips.replay import FrameSettings, make_render_env
from groupwise.clips.store import ClipStore
from groupwise.clips.timing import clip_timing, step_seconds
from groupwise.clips.video import VideoConfig
from groupwise.envs import make_env
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
from groupwise.rl.policy import Policy
from groupwise.types import ProgressFn

logger = logging.getLogger(__name__)

STORE_DIR = "clips"
__all__ = ["FORMAT", "PoolTimings", "PreparedPool", "load_fragments"]  # re-exported


@dataclass(frozen=True)
class PublishConfig:
    """How a sampled pool is published: its clips, tree and group candidates.

    What pool it is (env steps, N behaviours of L steps) is the sampler's business: the run
    config's `LoopConfig` in the app, `prepare_pool`'s arguments for `groupwise pool`."""

    env: str = "Hopper"
    """Short env name (`groupwise.envs.ENVS`) or Gymnasium id the pool was sampled in."""
    width: int = 240
    """Frame width in pixels (even)."""
    height: int = 240
    """Frame height in pixels (even)."""
    video: VideoConfig = field(default_factory=VideoConfig)
    """Clip and poster encoding."""
    tree: TreeConfig = field(default_factory=TreeConfig)
    """How the behaviour tree is cut (the run config's `RunConfig.tree`)."""
    candidate_levels: tuple[int, ...] = (1, 2)
    """Tree levels whose nodes are group candidates (SPEC §4)."""
    max_group: int = MAX_GROUP
    """Largest group candidate (smallest is 2)."""
    medoids: int = 3
    """Representative clips kept per inner tree node (hover previews, SPEC §9)."""
    workers: int = 2
    """Render worker processes (0: render in this process)."""
    clips: Literal["eager", "on_demand"] = "on_demand"
    """"on_demand": render a poster per behaviour now and keep each clip's recipe, so that
    a clip is rendered when it is first asked for (`clips.on_demand`, served by the app);
    "eager": render and encode every clip now (`groupwise pool`: a directory to use without
    a server). On demand by default: rendering every clip was 85 % of a 1,000-behaviour
    Hopper pool's CPU time and ~0.25 CPU-s a clip whatever the pool's size, while a person
    watches a few dozen clips a round (issue 22)."""

    def __post_init__(self) -> None:
        if self.width < 2 or self.height < 2 or self.width % 2 or self.height % 2:
            raise ValueError(f"frame size must be even, got {self.width}×{self.height}")
        if self.workers < 0:
            raise ValueError(f"workers must be >= 0, got {self.workers}")


def prepare_pool(
    cfg: PublishConfig,
    policy: Policy,
    rng: np.random.Generator,
    out: Path,
    *,
    size: int,
    length: int,
    oversample: float = 1.0,
    exploration_fraction: float = 0.0,
    store: ClipStore | None = None,
    render_pool: RenderPool | None = None,
    metadata: Mapping[str, Any] | None = None,
    show_progress: bool = True,
) -> PreparedPool:
    """Sample `size` behaviours of `length` steps from `policy` in `cfg.env` (a random
    subset of `oversample` × `size` windows, a share `exploration_fraction` of the steps
    random: `sampling.sample_pool`) and publish them into `out` (`publish_pool`).

    Raises:
        ValueError: as `sample_pool` (e.g. `size` < 1, `oversample` < 1, an exploration
            fraction outside [0, 1)) and `publish_pool`.
    """
    tick = time.perf_counter()
    pool = sample_pool(
        lambda: make_env(cfg.env),
        policy,
        size,
        length,
        rng,
        exploration_fraction=exploration_fraction,
        oversample=oversample,
    )
    sample_s = time.perf_counter() - tick
    return publish_pool(
        cfg,
        pool,
        out,
        oversample=oversample,
        exploration_fraction=exploration_fraction,
        store=store,
        render_pool=render_pool,
        metadata=metadata,
        show_progress=show_progress,
        sample_s=sample_s,
    )


def publish_pool(
    cfg: PublishConfig,
    pool: BehaviourPool,
    out: Path,
    *,
    oversample: float = 1.0,
    exploration_fraction: float = 0.0,
    store: ClipStore | None = None,
    render_pool: RenderPool | None = None,
    metadata: Mapping[str, Any] | None = None,
    show_progress: bool = True,
    sample_s: float = 0.0,
    progress: ProgressFn | None = None,
) -> PreparedPool:
    """Render, encode, cluster and write a sampled pool (module docstring).

    `pool.episodes` must hold the episodes its fragments were cut from (they are replayed
    into clips). `store` defaults to ``out/clips``; `render_pool` (reused across rounds by
    a long-lived caller) defaults to a fresh one with `cfg.workers` workers, closed on
    return. `metadata` (e.g. policy and seed) is written into ``pool.json``, and beside
    `cfg` under "config" how the pool was sampled (N and L, read off `pool`; `oversample` and
    `exploration_fraction` as given to `sample_pool`: only recorded); `sample_s`, the time it
    took to sample the pool, into the timings. `progress` hears (clips done, clips) as the
    workers render them (`clips.render.PendingClips.wait`).

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
        jobs: list[ClipJob] | list[PosterJob]
        if cfg.clips == "on_demand":
            jobs = plan_poster_jobs(trajectories, fragments, settings, timing, workers.workers)
        else:
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
        distances = pool.measure_distances(cfg=cfg.tree)
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
        reports = pending.wait(show_progress, progress)
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
        frames=len(fragments) * (timing.frames if cfg.clips == "eager" else 1),
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
    config = {
        "env": cfg.env,
        "size": len(fragments),
        "length": timing.steps,
        "oversample": oversample,
        "exploration_fraction": exploration_fraction,
        **dataclasses.asdict(cfg),
    }
    write_pool(prepared, pool, representatives, config, metadata or {})
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
