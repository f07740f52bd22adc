"""The worker's jobs: the two halves of a round, run apart in time because a person answers
in between (`groupwise.run.round`), on the session's `Run` in ``DIR/sessions/<session>/``.

prepare round r: the run as round r − 1 left it (`Run.restore`) → `begin_round` with the
    session's query strategy (the Groupwise-DM's group suggestions, or the Pairwise-DM's
    queries in pairwise mode) → `publish_offer`: clips into the shared store ``DIR/clips``,
    the tree and candidates (`pool.publish.publish_pool`), the queries as the page's
    suggestions and pairwise queue (`offers`), stored in one transaction that opens the round.
train after round r: the run as round r − 1 left it → the round's stored judgements (not
    undone, each keyed by its place in the round) → `end_round`: pairs, dataset, reward fit,
    PPO for `ppo_steps_per_round`, evaluation, checkpoint and ``rounds.csv`` → round r + 1
    preparing, or finishing.

A person and a simulated decision-maker therefore answer the same queries, and their
answers become training by the same function.
"""

import json
import logging
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING

from groupwise.agent_file.summary import SETTINGS_FILE
from groupwise.behaviour import kernel_threads
from groupwise.behaviour.pool import BehaviourPool
from groupwise.clips.render import RenderPool
from groupwise.clips.store import ClipStore
from groupwise.config import RunConfig
from groupwise.oracles import STRATEGIES
from groupwise.pool.files import load_pool
from groupwise.pool.publish import PublishConfig, publish_pool
from groupwise.pool.sampling import windows_to_sample
from groupwise.preferences.judgement import Judgement
from groupwise.query.strategies import Query, QueryStrategy
from groupwise.rl.batch_envs import free_cores
from groupwise.run.checkpoint import STATE_FILE, checkpoint_dir
from groupwise.run.progress import RunCallback, as_callback
from groupwise.run.records import RoundRecord
from groupwise.run.round import Offer, begin_round, end_round, finish_round
from groupwise.run.run import Run
from groupwise.storage import Database, SessionSettings
from groupwise.storage.judgements import round_judgements
from groupwise.storage.lifecycle import finish_training, record_training
from groupwise.storage.phases import WORK_PHASES
from groupwise.storage.rounds import PreparedRound, store_prepared_round
from groupwise.storage.sessions import (
    get_round,
    get_session,
    round_directory,
    session_directory,
    settings_of,
)
from groupwise.storage.staging import open_staged as stage_opened
from groupwise.storage.staging import stage_round
from groupwise.storage.timer import elapsed
from groupwise.worker.offers import prepared_round
from groupwise.worker.progress import JobProgress

if TYPE_CHECKING:
    from groupwise.worker.live import LiveTraining

log = logging.getLogger(__name__)

QUEUE_FACTOR = 2
"""A round offers this many times its comparison budget in queries (skips use some up)."""


@dataclass(frozen=True)
class Job:
    """One step of one session, as the worker found it in the database."""

    session_id: str
    env: str
    mode: str  # "groupwise" or "pairwise"
    phase: str  # "preparing", "training" or "finishing"
    round: int
    settings: SessionSettings
    elapsed_s: float  # the round's timer when training started (for the round record)
    frozen_steps: int | None = None
    """PPO steps of the current round when it is one without feedback (`RoundRow`)."""


def open_run(job: Job, data_dir: Path, after: int) -> Run:
    """The session's run as round `after` left it (fresh for −1); writes its
    ``config.json`` and ``settings.json`` (the settings may have changed since: "Finish
    now", "Continue training")."""
    cfg = job.settings.run_config(job.env)
    out = data_dir / session_directory(job.session_id)
    run = Run.create(cfg, out)
    (out / SETTINGS_FILE).write_text(job.settings.model_dump_json(indent=2) + "\n")
    run.restore(after)
    return run


def session_strategy(cfg: RunConfig, mode: str) -> QueryStrategy:
    """What the page suggests: the Pairwise-DM's queries in pairwise mode, else the
    Groupwise-DM's group suggestions (`groupwise.oracles.STRATEGIES`)."""
    return STRATEGIES["pairwise" if mode == "pairwise" else "groupwise"](cfg)


def offered_queries(settings: SessionSettings) -> int:
    """How many queries a round offers: `QUEUE_FACTOR` × its budget (× its pool when it
    has no limit)."""
    return QUEUE_FACTOR * (settings.comparisons_per_round or settings.pool_size)


def prepare(
    job: Job, db: Database, data_dir: Path, render: RenderPool, progress: JobProgress
) -> None:
    """Prepare round `job.round`'s offer and open the round (module docstring)."""
    settings = job.settings
    progress.on_phase("load", 0, 1)
    # nothing else of this worker runs meanwhile: the distances take the free cores
    with open_run(job, data_dir, job.round - 1) as run, kernel_threads(free_cores()):
        offer = begin_round(
            run,
            session_strategy(run.cfg, job.mode),
            settings.comparisons_per_round,
            n_queries=offered_queries(settings),
            callback=progress,
        )
        steps = run.agent.num_timesteps
    publish_offer(
        db,
        data_dir,
        job.session_id,
        job.env,
        settings,
        offer.pool,
        offer.queries,
        render,
        progress=progress,
        sample_s=offer.sample_s,
        ppo_steps=steps,
    )
    log.info(
        "session %s: round %d ready (%d behaviours)", job.session_id, job.round, len(offer.pool)
    )


def publish_offer(
    db: Database,
    data_dir: Path,
    session_id: str,
    env: str,
    settings: SessionSettings,
    pool: BehaviourPool,
    queries: Sequence[Query],
    render: RenderPool,
    *,
    progress: JobProgress | None = None,
    sample_s: float = 0.0,
    ppo_steps: int | None = None,
) -> bool:
    """Publish `pool` as round `pool.round` of a session and open the round: clips, tree
    and candidates (`pool.publish.publish_pool`), then `queries` as the page's suggestions
    and pairwise queue, stored in one transaction. False (nothing opened) when the session
    moved on meanwhile."""
    prepared = published_round(
        data_dir, session_id, env, settings, pool, queries, render, progress, sample_s, ppo_steps
    )
    with db.write() as s:
        if not store_prepared_round(s, session_id, pool.round, prepared):
            log.warning("session %s moved on while round %d was prepared", session_id, pool.round)
            return False
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
) -> PreparedRound:
    """`pool` published as round `pool.round` (clips, tree, candidates in its directory)
    and what the database stores to open it; `ppo_steps`, the PPO steps of the policy that
    sampled it, goes into ``pool.json``'s metadata (`sampled_at`)."""
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
        metadata={"session": session_id, "round": pool.round, "ppo_steps": ppo_steps},
        show_progress=False,
        sample_s=sample_s,
        progress=None if progress is None else partial(progress.on_phase, "clips"),
    )
    if progress is not None:
        progress.on_phase("suggestions", 0, 1)
    return prepared_round(pool, published, queries, settings.suggestions)


def stage_next(job: Job, run: Run) -> Offer:
    """The offer of round `job.round + 1`, sampled ahead from the policy as it is now while
    round `job.round` is still open (continuous training); `publish_staged` publishes it."""
    settings = job.settings
    return begin_round(
        run,
        session_strategy(run.cfg, job.mode),
        settings.comparisons_per_round,
        n_queries=offered_queries(settings),
        round_index=job.round + 1,
    )


def publish_staged(
    job: Job, offer: Offer, db: Database, data_dir: Path, render: RenderPool, ppo_steps: int
) -> None:
    """Publish an offer prepared ahead (`stage_next`: clips, tree, candidates) into its
    round's directory and stage it in the database (`storage.staging`): the round's end
    opens it in the same transaction. Touches no run: the stager process calls it
    (`worker.staging`) while PPO goes on in the worker."""
    prepared = published_round(
        data_dir, job.session_id, job.env, job.settings, offer.pool, offer.queries, render,
        sample_s=offer.sample_s, ppo_steps=ppo_steps,
    )  # fmt: skip
    with db.write() as s:
        staged = stage_round(s, job.session_id, job.round + 1, prepared)
    log.info(
        "session %s: round %d %s",
        job.session_id,
        job.round + 1,
        "staged" if staged else "prepared ahead too late (the session moved on)",
    )


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


def train(
    job: Job,
    db: Database,
    data_dir: Path,
    progress: JobProgress,
    live: "LiveTraining | None" = None,
) -> None:
    """End round `job.round` on its stored judgements and queue the next round or the final
    phase (module docstring). With `live` (a continuous session's round, `worker.live`) the
    round's run is the one that trained while the person compared, the round adds no PPO
    steps of its own, and a next round prepared ahead (`stage_next`) opens *before* the
    round is committed: the person compares again while the worker fits, evaluates and
    checkpoints (a worker killed meanwhile commits it when it resumes: `worker.live`)."""
    r = job.round
    opened = live is not None and open_staged(job, db)
    record = commit_round(job, db, data_dir, progress, live)
    if live is not None:
        live.run.close()
    checkpoint = checkpoint_of(job.session_id, r)
    with db.write() as s:
        if opened:
            record_training(s, job.session_id, r, checkpoint, record.stats())
        elif not finish_training(s, job.session_id, r, checkpoint, record.stats()):
            log.warning("session %s moved on while round %d trained", job.session_id, r)
    log.info(
        "session %s: round %d trained on %d pairs (reward acc %.2f, true return %.1f)",
        job.session_id,
        r,
        record.pairs_total,
        record.reward_accuracy,
        record.true_return_mean,
    )


def checkpoint_of(session_id: str, round_index: int) -> str:
    """The checkpoint directory of a session's round, relative to the data directory."""
    return str(checkpoint_dir(Path(session_directory(session_id)), round_index))


def committed_record(data_dir: Path, session_id: str, round_index: int) -> RoundRecord | None:
    """The record of round `round_index` from its checkpoint on disk, when `end_round`
    wrote it (None when it did not: the round is still to be committed)."""
    state = data_dir / checkpoint_of(session_id, round_index) / STATE_FILE
    try:
        row = json.loads(state.read_text())["records"][-1]
    except (OSError, ValueError, KeyError, IndexError):
        return None
    return RoundRecord(**row) if row.get("round") == round_index else None


def open_staged(job: Job, db: Database) -> bool:
    """Open round `job.round + 1` from the offer prepared ahead (`stage_next`), before round
    `job.round` is committed, when the round ended before it was staged; False when none
    was prepared (or the session moved on)."""
    with db.write() as s:
        opened = stage_opened(s, job.session_id, job.round)
    if opened:
        log.info("session %s: round %d opened (prepared ahead)", job.session_id, job.round + 1)
    return opened


def commit_round(
    job: Job,
    db: Database,
    data_dir: Path,
    progress: RunCallback | None,
    live: "LiveTraining | None" = None,
) -> RoundRecord:
    """Commit round `job.round` on its stored judgements: on `live`'s run, its last fit
    brought up to date (`LiveRound.update`, as the headless continuous round ends: no PPO
    steps, no second fit of the same pairs) and left open for the next round; else
    `end_round` on the run as the round before left it (`ppo_steps_per_round`), closed."""
    settings, r = job.settings, job.round
    if progress is not None:
        progress.on_phase("load", 0, 1)
    with db.read() as s:
        pool_dir = get_round(s, job.session_id, r).pool_dir
        keyed = round_judgements(s, job.session_id, r)
    if live is not None:
        return _commit_live(live, keyed, job.elapsed_s, progress)
    if pool_dir is None:
        raise FileNotFoundError(f"round {r} has no pool directory")
    offer = published_offer(data_dir / pool_dir, r, settings.comparisons_per_round, job.mode)
    with open_run(job, data_dir, r - 1) as run:
        return end_round(
            run,
            offer,
            [judgement for _, judgement in keyed],
            settings.ppo_steps_per_round,
            keys=[key for key, _ in keyed],
            feedback_s=job.elapsed_s,
            callback=progress,
        )


def _commit_live(
    live: "LiveTraining",
    keyed: Sequence[tuple[int, Judgement]],
    feedback_s: float,
    progress: RunCallback | None,
) -> RoundRecord:
    round_ = live.live
    round_.update(keyed, time.monotonic(), final=True)
    round_.timer.seconds["feedback_s"] = feedback_s
    record = finish_round(
        live.run,
        round_.offer,
        [judgement for _, judgement in keyed],
        round_.report,
        round_.timer,
        as_callback(progress),
        asked=None,
    )
    live.run.drop_live()
    return record


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


def job_of(db: Database, session_id: str) -> Job | None:
    """The job a session waits for, or None when it waits for none."""
    with db.read() as s:
        session = get_session(s, session_id)
        if session.phase not in WORK_PHASES:
            return None
        return Job(
            session_id=session.id,
            env=session.env,
            mode=session.mode,
            phase=session.phase,
            round=session.round,
            settings=settings_of(session),
            elapsed_s=elapsed(session),
            frozen_steps=get_round(s, session.id, session.round).frozen_steps,
        )
