"""The worker's two jobs: prepare a round's pool, and train after a round (SPEC §3, §5).

Both are the headless loop's own phases (`groupwise.loop`), run apart in time because a
person answers in between: `loop.Session.create` wires the reward ensemble and PPO,
`Session.restore` / `Session.save` read and write the per-round checkpoints under
``DIR/sessions/<session>/checkpoints/round-NNNN/`` (and ``rounds.csv`` beside them, as
`groupwise train` writes).

prepare round r: the PPO checkpoint of round r − 1 (a fresh policy for r = 0) →
    `loop.sample_pool` (exploration 0.25, the windows the ensemble is most uncertain about)
    → `prepare.publish_pool` (clips into the shared store ``DIR/clips``, tree, candidates)
    → group suggestions over the tree's candidates, top-k pairwise edges and the pairwise
    baseline's queue (`server.suggestions`) → stored in one transaction, which opens the
    round.
train after round r: the dataset of every stored, non-undone pair of the session (pairs
    derived by the session's `pair_derivation` when stored, capped per round by
    `loop.limit_pairs`) → `loop.train_round`: fit the ensemble → PPO for
    `ppo_steps_per_round` on the learned reward → evaluate on the true reward → checkpoint
    → round r + 1 preparing, or finished.

Randomness: round r draws from the loop's streams of that round (`loop.round_streams`):
the prepare job from its sample and feedback streams, training from its fit and PPO
streams; nothing global.
"""

import dataclasses
import json
import logging
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from sqlalchemy.orm import Session as OrmSession

from groupwise.checkpoint import STATE_FILE, checkpoint_dir
from groupwise.clips.render import RenderPool
from groupwise.clips.store import ClipStore
from groupwise.config import RunConfig
from groupwise.loop import (
    CONFIG_FILE,
    RESULTS_FILE,
    RoundRecord,
    Session,
    limit_pairs,
    round_streams,
    sample_pool,
    train_round,
    write_records,
)
from groupwise.pool import BehaviourPool, behaviour_index
from groupwise.preferences.dataset import PreferenceDataset
from groupwise.preferences.pairs import Pair
from groupwise.prepare import PoolConfig, PreparedPool, load_fragments, publish_pool
from groupwise.query.groups import return_variance
from groupwise.query.strategies import Query
from groupwise.server.progress import ProgressReporter
from groupwise.server.suggestions import (
    group_suggestions,
    pairwise_edges,
    pairwise_queue,
    suggestions_of,
)
from groupwise.storage import Database, SessionSettings
from groupwise.storage.judgements import PairRecord, live_judgement_counts, live_pairs
from groupwise.storage.rounds import (
    BehaviourInput,
    PreparedRound,
    store_prepared_round,
)
from groupwise.storage.sessions import (
    WORK_PHASES,
    counts,
    elapsed,
    finish_training,
    get_round,
    get_session,
    round_directory,
    session_directory,
    settings_of,
)
from groupwise.trained_agent import SETTINGS_FILE

log = logging.getLogger(__name__)

QUEUE_FACTOR = 2
"""The pairwise queue holds this many times the round's comparisons (skips use some up)."""


@dataclass(frozen=True)
class Job:
    """One step of one session, as the worker found it in the database."""

    session_id: str
    env: str
    phase: str  # "preparing", "training" or "finishing"
    round: int
    settings: SessionSettings
    elapsed_s: float  # the round's timer when training started (for the round record)
    frozen_steps: int | None = None
    """PPO steps of the current round when it is one without feedback (`RoundRow`)."""


def run_config(env: str, settings: SessionSettings) -> RunConfig:
    """The core's configuration of a session (written as ``config.json`` beside it)."""
    return settings.run_config(env)


def load_session(job: Job, data_dir: Path, before: int) -> tuple[RunConfig, Session, Path]:
    """The session's ensemble and agent as they were after round `before` (fresh for -1);
    writes its ``config.json`` and ``settings.json`` (the settings may have changed since:
    "Finish now", "Continue training")."""
    cfg = run_config(job.env, job.settings)
    out = data_dir / session_directory(job.session_id)
    out.mkdir(parents=True, exist_ok=True)
    cfg.save(out / CONFIG_FILE)
    (out / SETTINGS_FILE).write_text(job.settings.model_dump_json(indent=2) + "\n")
    session = Session.create(cfg, out)
    if before >= 0:
        directory = checkpoint_dir(out, before)
        state = json.loads((directory / STATE_FILE).read_text())
        session.restore(directory, state)
    return cfg, session, out


def prepare(
    job: Job, db: Database, data_dir: Path, render: RenderPool, progress: ProgressReporter
) -> None:
    """Prepare round `job.round`'s pool and open the round (module docstring)."""
    settings, r = job.settings, job.round
    streams = round_streams(settings.seed, r)
    progress.report("load", 0.02, "loading the policy and reward model", force=True)
    _, session, _ = load_session(job, data_dir, r - 1)
    try:
        progress.report(
            "pool", 0.05, f"sampling and rendering {settings.pool_size} behaviours", force=True
        )
        tick = time.perf_counter()
        pool = sample_pool(session, r, settings.pool_size, streams.sample)
        sample_s = time.perf_counter() - tick
    finally:
        session.ppo.close()
    publish_round(
        db,
        data_dir,
        job.session_id,
        job.env,
        settings,
        pool,
        render,
        streams.feedback,
        progress=progress,
        sample_s=sample_s,
    )
    log.info("session %s: round %d ready (%d behaviours)", job.session_id, r, len(pool))


def publish_round(
    db: Database,
    data_dir: Path,
    session_id: str,
    env: str,
    settings: SessionSettings,
    pool: BehaviourPool,
    render: RenderPool,
    rng: np.random.Generator,
    *,
    queries: Sequence[Query] | None = None,
    progress: ProgressReporter | None = None,
    sample_s: float = 0.0,
) -> bool:
    """Publish `pool` as round `pool.round` of a session and open the round: clips, tree
    and candidates (`prepare.publish_pool`), then the round's suggestions (`prepared_round`)
    stored in one transaction. False (nothing opened) when the session moved on meanwhile."""
    published = publish_pool(
        pool_config(env, settings, render.workers),
        pool,
        data_dir / round_directory(session_id, pool.round),
        store=ClipStore(data_dir / "clips"),
        render_pool=render,
        metadata={"session": session_id, "round": pool.round},
        show_progress=False,
        sample_s=sample_s,
    )
    if progress is not None:
        progress.report("suggestions", 0.9, "computing suggestions", force=True)
    prepared = prepared_round(pool, published, settings, rng, queries)
    with db.write() as s:
        if not store_prepared_round(s, session_id, pool.round, prepared):
            log.warning("session %s moved on while round %d was prepared", session_id, pool.round)
            return False
    return True


def pool_config(env: str, settings: SessionSettings, workers: int) -> PoolConfig:
    """How the app publishes a session's pools."""
    return PoolConfig(
        env=env,
        size=settings.pool_size,
        length=settings.clip_timing(env).steps,
        exploration_fraction=settings.exploration_fraction,
        width=settings.frame_size,
        height=settings.frame_size,
        workers=workers,
    )


def prepared_round(
    pool: BehaviourPool,
    published: PreparedPool,
    settings: SessionSettings,
    rng: np.random.Generator,
    queries: Sequence[Query] | None = None,
) -> PreparedRound:
    """What the database stores to open a round: the behaviours, the group suggestions over
    the tree's candidates, the top-k pairwise edges and the pairwise baseline's queue.

    Given `queries` (a query strategy's proposals), they are the round's suggestions (groups)
    and its pairwise queue (pairs) instead, in their order."""
    returns = pool.predicted_returns
    intra = pool.step_variance
    if intra is None:
        intra = return_variance(returns, pool.fragments[0].length)
    suggestions = group_suggestions(returns, intra, published.candidates)
    queue = pairwise_queue(
        returns, QUEUE_FACTOR * (settings.comparisons_per_round or settings.pool_size), rng
    )
    if queries is not None:
        suggestions, queue = suggestions_of(queries, published.tree, returns)
    return PreparedRound(
        behaviours=tuple(
            BehaviourInput(i, published.clips[i], published.posters[i], f.true_return)
            for i, f in enumerate(pool.fragments)
        ),
        suggestions=suggestions,
        edges=pairwise_edges(returns, settings.suggestions),
        queue=queue,
    )


def train(job: Job, db: Database, data_dir: Path, progress: ProgressReporter) -> None:
    """Fit the reward model on every pair so far, train PPO, checkpoint (module docstring):
    `loop.train_round`, on the dataset of the stored judgements."""
    settings, r = job.settings, job.round
    streams = round_streams(settings.seed, r)
    progress.report("load", 0.01, "loading the policy and reward model", force=True)
    cfg, session, out = load_session(job, data_dir, r - 1)
    steps = settings.ppo_steps_per_round
    try:
        with db.read() as s:
            pairs = live_pairs(s, job.session_id)
            pool_dirs = {
                i: get_round(s, job.session_id, i).pool_dir for i in sorted({p[0] for p in pairs})
            }
            judged = _judgements_in_round(s, job.session_id, r)
            per_round = live_judgement_counts(s, job.session_id)
        session.dataset = _dataset(cfg, data_dir, pairs, pool_dirs, per_round, session)
        phases = {
            "reward": (0.03, lambda done, total: f"fitting the reward model on {total} pairs"),
            "ppo": (0.1, lambda done, total: f"PPO {done:,} / {total:,} steps"),
            "eval": (0.92, lambda done, total: "measuring the policy's true return"),
        }

        def report(phase: str, done: int, total: int) -> None:
            start, message = phases[phase]
            fraction = start + 0.8 * done / max(total, 1) if phase == "ppo" else start
            progress.report(phase, fraction, message(done, total), force=phase != "ppo")

        record = train_round(
            session,
            r,
            comparisons=settings.comparisons_per_round,
            judgements=judged,
            steps=steps,
            streams=streams,
            seconds={
                "sample_s": _pool_seconds(data_dir / round_directory(job.session_id, r)),
                "feedback_s": job.elapsed_s,
            },
            report=report,
        )
        progress.report("checkpoint", 0.97, "saving the checkpoint", force=True)
        session.save(out)
        write_records(out / RESULTS_FILE, session.records)
    finally:
        session.ppo.close()
    checkpoint = checkpoint_dir(Path(session_directory(job.session_id)), r)
    with db.write() as s:
        if not finish_training(s, job.session_id, r, str(checkpoint), record_stats(record)):
            log.warning("session %s moved on while round %d trained", job.session_id, r)
    log.info(
        "session %s: round %d trained on %d pairs (reward acc %.2f, true return %.1f)",
        job.session_id,
        r,
        record.pairs_total,
        record.reward_accuracy,
        record.true_return_mean,
    )


def record_stats(record: RoundRecord) -> dict[str, object]:
    """A round's record as the database stores it (`RoundRow.stats`; nan as null)."""
    return {
        k: (None if isinstance(v, float) and not math.isfinite(v) else v)
        for k, v in dataclasses.asdict(record).items()
    }


def _dataset(
    cfg: RunConfig,
    data_dir: Path,
    pairs: list[tuple[int, PairRecord]],
    pool_dirs: dict[int, str | None],
    judgements: dict[int, int],
    session: Session,
) -> PreferenceDataset:
    """The cumulative dataset of the stored pairs, fragments read from each round's pool;
    each round's pairs capped as the loop caps them (`loop.limit_pairs`)."""
    dataset = PreferenceDataset.empty(
        cfg.loop.fragment_length, session.ensemble.obs_dim, session.ensemble.act_dim
    )
    for index, pool_dir in pool_dirs.items():
        if pool_dir is None:
            raise FileNotFoundError(f"round {index} has no pool directory")
        fragments = load_fragments(data_dir / pool_dir)
        round_pairs = [
            Pair(behaviour_index(p.a), behaviour_index(p.b), p.label)
            for r, p in pairs
            if r == index
        ]
        rng = round_streams(cfg.loop.seed, index).pairs
        kept = limit_pairs(round_pairs, cfg.loop, judgements.get(index, 0), rng)
        dataset.add(fragments, kept, index)
    return dataset


def _judgements_in_round(s: OrmSession, session_id: str, r: int) -> int:
    session = get_session(s, session_id)
    return counts(s, session).comparisons_round if session.round == r else 0


def _pool_seconds(directory: Path) -> float:
    try:
        return float(json.loads((directory / "timings.json").read_text())["total_s"])
    except (OSError, ValueError, KeyError):
        return float("nan")


def job_of(db: Database, session_id: str) -> Job | None:
    """The job a session waits for, or None when it waits for none."""
    with db.read() as s:
        session = get_session(s, session_id)
        if session.phase not in WORK_PHASES:
            return None
        return Job(
            session_id=session.id,
            env=session.env,
            phase=session.phase,
            round=session.round,
            settings=settings_of(session),
            elapsed_s=elapsed(session),
            frozen_steps=get_round(s, session.id, session.round).frozen_steps,
        )
