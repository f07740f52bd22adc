"""The worker's two jobs: prepare a round's pool, and train after a round (SPEC §3, §5).

Both compose the core exactly as `groupwise.loop` does: `loop.Session.create` wires the
reward ensemble and PPO (the policy trains on the ensemble mean), `Session.restore` /
`Session.save` read and write the per-round checkpoints under
``DIR/sessions/<session>/checkpoints/round-NNNN/``. What differs from the simulated loop is
who answers (a person, through the database) and that the steps run apart in time.

prepare round r: policy = random (r = 0) or the PPO checkpoint of round r − 1 →
    `prepare_pool` (exploration 0.25, the windows the ensemble is most uncertain about for
    r > 0, clips into the shared store ``DIR/clips``) → the ensemble's N × K predicted
    returns and per-behaviour step variance → group suggestions over the tree's candidates
    (`suggest_groups`), top-k pairwise edges (`top_pairs`) and the pairwise baseline's queue
    (`select_pairs`) → stored in one transaction, which opens the round.
train after round r: the dataset of every stored, non-undone pair of the session → `fit`
    the ensemble → PPO for `ppo_steps_per_round` on the learned reward → evaluate on the
    true reward → checkpoint → round r + 1 preparing, or finished.

Randomness: round r's prepare job draws from ``SeedSequence([seed, r, PREPARE_STREAM])``,
its training from ``SeedSequence([seed, r, TRAIN_STREAM])``; nothing global.
"""

import dataclasses
import json
import logging
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from sqlalchemy.orm import Session as OrmSession

from groupwise.checkpoint import STATE_FILE, checkpoint_dir
from groupwise.fragments import stack_fragments
from groupwise.clips.render import RenderPool
from groupwise.clips.store import ClipStore
from groupwise.config import LoopConfig, PPOConfig, RewardConfig, RunConfig
from groupwise.loop import CONFIG_FILE, POOL_OVERSAMPLE, RoundRecord, Session
from groupwise.preferences.dataset import PreferenceDataset, wrong_labels
from groupwise.preferences.pairs import Pair
from groupwise.prepare import PoolConfig, load_fragments, prepare_pool
from groupwise.query.groups import step_variance
from groupwise.reward import fit
from groupwise.rl.policy import Policy, RandomPolicy
from groupwise.rl.rollout import evaluate
from groupwise.server.progress import ProgressReporter
from groupwise.server.suggestions import group_suggestions, pairwise_edges, pairwise_queue
from groupwise.storage import Database, SessionSettings
from groupwise.storage.judgements import PairRecord, live_pairs
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
from groupwise.storage.settings import MAX_GROUP

log = logging.getLogger(__name__)

PREPARE_STREAM = 2
TRAIN_STREAM = 3
QUEUE_FACTOR = 2
"""The pairwise queue holds this many times the round's comparisons (skips use some up)."""


@dataclass(frozen=True)
class Job:
    """One step of one session, as the worker found it in the database."""

    session_id: str
    env: str
    phase: str  # "preparing" or "training"
    round: int
    settings: SessionSettings
    elapsed_s: float  # the round's timer when training started (for the round record)


def run_config(env: str, settings: SessionSettings) -> RunConfig:
    """The core's configuration of a session (written as ``config.json`` beside it)."""
    ppo: dict[str, Any] = {
        k: tuple(v) if isinstance(v, list) else v for k, v in settings.ppo if v is not None
    }
    reward: dict[str, Any] = {k: v for k, v in settings.reward if v is not None}
    loop = LoopConfig(
        env=env,
        oracle="pairwise",  # unused: a person answers
        comparisons=max(1, settings.comparisons_per_round * settings.rounds),
        rounds=settings.rounds,
        steps=settings.ppo_steps_per_round * settings.rounds,
        fragment_length=settings.fragment_length,
        exploration_fraction=settings.exploration_fraction,
        pool_cap=max(2, settings.pool_size),
        eval_episodes=max(1, settings.eval_episodes),
        max_group_size=MAX_GROUP,
        seed=settings.seed,
    )
    return RunConfig(
        loop=loop,
        reward=dataclasses.replace(RewardConfig(), **reward),
        ppo=dataclasses.replace(PPOConfig(), **ppo),
    )


def _load(job: Job, data_dir: Path, before: int) -> tuple[RunConfig, Session, Path]:
    """The session's ensemble and agent as they were after round `before` (fresh for -1)."""
    cfg = run_config(job.env, job.settings)
    out = data_dir / session_directory(job.session_id)
    out.mkdir(parents=True, exist_ok=True)
    cfg.save(out / CONFIG_FILE)
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
    sample_rng, queue_rng = np.random.default_rng(
        np.random.SeedSequence([settings.seed, r, PREPARE_STREAM])
    ).spawn(2)
    progress.report("load", 0.02, "loading the policy and reward model", force=True)
    _, session, _ = _load(job, data_dir, r - 1)
    try:
        ensemble = session.ensemble
        policy: Policy = session.agent.policy() if r > 0 else _random_policy(session)
        pool_cfg = PoolConfig(
            env=job.env,
            size=settings.pool_size,
            length=settings.fragment_length,
            oversample=1.0 if r == 0 else POOL_OVERSAMPLE,
            exploration_fraction=settings.exploration_fraction,
            width=settings.frame_size,
            height=settings.frame_size,
            max_group=MAX_GROUP,
            workers=render.workers,
        )
        progress.report(
            "pool", 0.05, f"sampling and rendering {settings.pool_size} behaviours", force=True
        )
        pool = prepare_pool(
            pool_cfg,
            policy,
            sample_rng,
            data_dir / round_directory(job.session_id, r),
            store=ClipStore(data_dir / "clips"),
            render_pool=render,
            uncertainty=None if r == 0 else lambda obs, acts: ensemble.returns(obs, acts).var(1),
            metadata={"session": job.session_id, "round": r},
            show_progress=False,
        )
    finally:
        session.agent.close()
    progress.report("suggestions", 0.9, "computing suggestions", force=True)
    obs, acts = stack_fragments(pool.fragments)
    step = ensemble.step_rewards(obs, acts)  # (K, N, L)
    returns = np.ascontiguousarray(step.sum(axis=-1).T)  # (N, K)
    prepared = PreparedRound(
        behaviours=tuple(
            BehaviourInput(i, pool.clips[i], pool.posters[i], f.true_return)
            for i, f in enumerate(pool.fragments)
        ),
        suggestions=group_suggestions(returns, step_variance(step), pool.candidates),
        edges=pairwise_edges(returns, settings.suggestions),
        queue=pairwise_queue(
            returns,
            QUEUE_FACTOR * (settings.comparisons_per_round or settings.pool_size),
            queue_rng,
        ),
    )
    with db.write() as s:
        if not store_prepared_round(s, job.session_id, r, prepared):
            log.warning("session %s moved on while round %d was prepared", job.session_id, r)
    log.info("session %s: round %d ready (%d behaviours)", job.session_id, r, len(pool.fragments))


def _random_policy(session: Session) -> Policy:
    return RandomPolicy(session.agent.venv.action_space)


def train(job: Job, db: Database, data_dir: Path, progress: ProgressReporter) -> None:
    """Fit the reward model on every pair so far, train PPO, checkpoint (module docstring)."""
    settings, r = job.settings, job.round
    fit_rng, ppo_rng, eval_rng = np.random.default_rng(
        np.random.SeedSequence([settings.seed, r, TRAIN_STREAM])
    ).spawn(3)
    progress.report("load", 0.01, "loading the policy and reward model", force=True)
    cfg, session, out = _load(job, data_dir, r - 1)
    try:
        with db.read() as s:
            pairs = live_pairs(s, job.session_id)
            pool_dirs = {
                i: get_round(s, job.session_id, i).pool_dir for i in sorted({p[0] for p in pairs})
            }
            judged = _judgements_in_round(s, job.session_id, r)
        session.dataset = _dataset(
            cfg, data_dir, pairs, pool_dirs, session.ensemble.obs_dim, session.ensemble.act_dim
        )
        tick = time.perf_counter()
        progress.report(
            "reward", 0.03, f"fitting the reward model on {len(session.dataset)} pairs", force=True
        )
        multiplier = cfg.reward.initial_epoch_multiplier if r == 0 else 1.0
        epochs = max(1, round(cfg.reward.epochs * multiplier))
        report = fit(session.ensemble, session.dataset, cfg.reward, fit_rng, epochs)
        reward_s = time.perf_counter() - tick

        tick = time.perf_counter()
        steps = settings.ppo_steps_per_round

        def ppo_progress(done: int, total: int) -> None:
            progress.report(
                "ppo", 0.1 + 0.8 * done / max(total, 1), f"PPO {done:,} / {total:,} steps"
            )

        ppo_progress(0, steps)
        session.agent.learn(steps, int(ppo_rng.integers(2**31 - 1)), report=ppo_progress)
        ppo_s = time.perf_counter() - tick

        tick = time.perf_counter()
        returns = np.full(1, np.nan)
        if settings.eval_episodes > 0:
            progress.report("evaluate", 0.92, "measuring the policy's true return", force=True)
            policy = session.agent.policy(deterministic=True)
            returns = evaluate(session.make_env, policy, settings.eval_episodes, eval_rng)
        eval_s = time.perf_counter() - tick

        dataset = session.dataset
        this_round = dataset.rounds == r
        record = RoundRecord(
            round=r,
            comparisons=settings.comparisons_per_round,
            judgements=judged,
            pairs=int(this_round.sum()),
            pairs_total=len(dataset),
            label_error_rate=_error_rate(dataset, this_round),
            label_error_rate_total=dataset.label_error_rate(),
            reward_loss=report.loss,
            reward_accuracy=report.accuracy,
            reward_val_accuracy=report.validation_accuracy,
            env_steps=session.agent.num_timesteps,
            true_return_mean=float(returns.mean()),
            true_return_std=float(returns.std()),
            sample_s=_pool_seconds(data_dir / round_directory(job.session_id, r)),
            feedback_s=job.elapsed_s,
            reward_s=reward_s,
            ppo_s=ppo_s,
            eval_s=eval_s,
        )
        session.records.append(record)
        progress.report("checkpoint", 0.97, "saving the checkpoint", force=True)
        session.save(out)
    finally:
        session.agent.close()
    checkpoint = checkpoint_dir(Path(session_directory(job.session_id)), r)
    stats = {
        k: (None if isinstance(v, float) and not math.isfinite(v) else v)
        for k, v in dataclasses.asdict(record).items()
    }
    with db.write() as s:
        if not finish_training(s, job.session_id, r, str(checkpoint), stats):
            log.warning("session %s moved on while round %d trained", job.session_id, r)
    log.info(
        "session %s: round %d trained on %d pairs (reward acc %.2f, true return %.1f)",
        job.session_id,
        r,
        record.pairs_total,
        record.reward_accuracy,
        record.true_return_mean,
    )


def _dataset(
    cfg: RunConfig,
    data_dir: Path,
    pairs: list[tuple[int, PairRecord]],
    pool_dirs: dict[int, str | None],
    obs_dim: int,
    act_dim: int,
) -> PreferenceDataset:
    """The cumulative dataset of the stored pairs, fragments read from each round's pool."""
    fragments_by_round = {}
    for index, pool_dir in pool_dirs.items():
        if pool_dir is None:
            raise FileNotFoundError(f"round {index} has no pool directory")
        fragments_by_round[index] = load_fragments(data_dir / pool_dir)
    dataset = PreferenceDataset.empty(cfg.loop.fragment_length, obs_dim, act_dim)
    for index, fragments in fragments_by_round.items():
        round_pairs = [Pair(int(p.a[1:]), int(p.b[1:]), p.label) for r, p in pairs if r == index]
        dataset.add(fragments, round_pairs, index)
    return dataset


def _judgements_in_round(s: OrmSession, session_id: str, r: int) -> int:
    session = get_session(s, session_id)
    return counts(s, session).comparisons_round if session.round == r else 0


def _error_rate(dataset: PreferenceDataset, mask: np.ndarray) -> float:
    if not mask.any():
        return float("nan")
    t = dataset.true_returns
    pairs = dataset.pairs[mask]
    return float(wrong_labels(t[pairs[:, 0]], t[pairs[:, 1]], dataset.labels[mask]).mean())


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
        )
