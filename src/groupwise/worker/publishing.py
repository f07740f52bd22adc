"""A round's offer published for the page: its clips, tree and candidates in the round's
directory (`pool.publish.publish_pool`), its queries as the page's suggestions and pairwise
queue (`offers`), stored in one transaction that opens the round (`publish_offer`); and a
published round read back (`published_offer`, `sampled_at`).
"""

import json
import logging
import math
from collections.abc import Sequence
from functools import partial
from pathlib import Path

from groupwise.behaviour.pool import BehaviourPool
from groupwise.clips.render import RenderPool
from groupwise.clips.store import ClipStore
from groupwise.config import RunConfig
from groupwise.pool.files import load_pool
from groupwise.pool.publish import PublishConfig, publish_pool
from groupwise.pool.sampling import windows_to_sample
from groupwise.query.strategies import Query
from groupwise.run.round import Offer
from groupwise.storage import Database, SessionSettings
from groupwise.storage.rounds import PreparedRound, store_prepared_round
from groupwise.storage.sessions import round_directory
from groupwise.storage.training import opening_point
from groupwise.worker.offers import prepared_round
from groupwise.worker.progress import JobProgress

log = logging.getLogger(__name__)


def publish_offer(
    db: Database,
    session_id: str,
    round_index: int,
    prepared: PreparedRound,
    ppo_steps: int | None = None,
) -> bool:
    """Open round `round_index` of a session with its offer published by `published_round`
    (clips, tree and candidates in its directory; its queries as the page's suggestions and
    pairwise queue), stored in one transaction; with `ppo_steps` (a session with an agent,
    whose policy at `ppo_steps` played the pool) the round's opening point of the learning
    curve in the same transaction (`storage.training.opening_point`). False (nothing
    opened) when the session moved on meanwhile."""
    with db.write() as s:
        if not store_prepared_round(s, session_id, round_index, prepared):
            log.warning("session %s moved on while round %d was prepared", session_id, round_index)
            return False
        if ppo_steps is not None:
            opening_point(s, session_id, round_index, ppo_steps)
    return True


def published_round(
    data_dir: Path,
    session_id: str,
    env: str,
    settings: SessionSettings,
    pool: BehaviourPool,
    queries: Sequence[Query],
    render: RenderPool,
    progress: JobProgress | None = None,
    sample_s: float = 0.0,
    ppo_steps: int | None = None,
    ages: Sequence[int] | None = None,
) -> PreparedRound:
    """`pool` published as round `pool.round` (clips, tree, candidates in its directory)
    and what the database stores to open it; `ppo_steps`, the PPO steps of the policy that
    sampled it (its oldest behaviour but the kept policy's share, `run.kept_policy`), goes
    into ``pool.json``'s metadata (`sampled_at`), and so do `ages`, each behaviour's age in
    PPO steps when the round opens (fresh pools, `pool.recent.pool_ages`)."""
    if progress is not None:
        progress.on_phase("clips", 0, len(pool))
    run_config = settings.run_config(env)
    loop = run_config.loop
    windows = windows_to_sample(len(pool), loop.pool_oversample, loop.pool_windows_max)
    published = publish_pool(
        publish_config(run_config, settings.frame_size, render.workers),
        pool,
        data_dir / round_directory(session_id, pool.round),
        oversample=windows / len(pool),  # as sampled: 1,000 behaviours of 1,000 windows
        exploration_fraction=loop.exploration_fraction,
        store=ClipStore(data_dir / "clips"),
        render_pool=render,
        metadata={
            "session": session_id,
            "round": pool.round,
            "ppo_steps": ppo_steps,
            **({} if ages is None else {"ages": [int(a) for a in ages]}),
        },
        show_progress=False,
        sample_s=sample_s,
        progress=None if progress is None else partial(progress.on_phase, "clips"),
    )
    if progress is not None:
        progress.on_phase("suggestions", 0, 1)
    return prepared_round(pool, published, queries, settings.suggestions)


def sampled_at(directory: Path) -> int | None:
    """PPO steps of the policy that sampled the pool published in `directory` (None when
    its ``pool.json`` does not say)."""
    try:
        steps = json.loads((directory / "pool.json").read_text())["metadata"]["ppo_steps"]
    except (OSError, ValueError, KeyError):
        return None
    return int(steps) if steps is not None else None


def publish_config(cfg: RunConfig, frame_size: int, workers: int) -> PublishConfig:
    """How the app publishes a session's pools (sampled as `cfg.loop` says)."""
    return PublishConfig(
        env=cfg.loop.env, width=frame_size, height=frame_size, tree=cfg.tree, workers=workers
    )


def published_offer(directory: Path, round_index: int, budget: int, mode: str) -> Offer:
    """The offer of a published round, as `end_round` needs it: the pool read back from its
    directory (its tree and queries live in the database and the page; group candidates are
    counted in groupwise mode, as the Groupwise-DM's strategy counts them)."""
    pool = load_pool(directory, round_index)
    try:
        timings = json.loads((directory / "timings.json").read_text())
        candidates = json.loads((directory / "candidates.json").read_text())["candidates"]
        sample_s = float(timings["total_s"])
        offered = float(len(candidates)) if mode != "pairwise" else math.nan
    except (OSError, ValueError, KeyError):
        sample_s, offered = math.nan, math.nan
    return Offer(pool, None, (), budget, candidates=offered, sample_s=sample_s)
