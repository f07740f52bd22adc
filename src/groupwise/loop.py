"""The RLHF loop (SPEC §3), readable top to bottom.

Per round: sample a pool from the current policy → gather comparisons from the oracle →
derive preference pairs → fit the reward ensemble on the cumulative dataset → train PPO on
the learned reward → evaluate on the true reward → checkpoint. Every round draws its
randomness from a generator derived from (seed, round), so a session resumed from a
checkpoint repeats exactly what an uninterrupted one does.
"""

import csv
import dataclasses
import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

from groupwise.checkpoint import (
    DATASET_FILE,
    REWARD_FILE,
    latest_checkpoint,
    write_checkpoint,
)
from groupwise.fragments import most_uncertain, stack_fragments, tile_fragments
from groupwise.config import RunConfig
from groupwise.envs import make_env
from groupwise.envs.spaces import action_dim, observation_dim
from groupwise.oracles import ORACLES, Oracle
from groupwise.pool import BehaviourPool
from groupwise.preferences.dataset import PreferenceDataset, wrong_labels
from groupwise.preferences.pairs import PAIR_DERIVATIONS, Pair, cap_pairs
from groupwise.query.groups import step_variance
from groupwise.query.schedule import comparisons_per_round
from groupwise.reward import RewardEnsemble, fit
from groupwise.rl.policy import Policy
from groupwise.rl.ppo import PPOAgent
from groupwise.rl.rollout import EnvFactory, evaluate, sample_trajectories

log = logging.getLogger(__name__)

CONFIG_FILE = "config.json"
RESULTS_FILE = "rounds.csv"
POOL_OVERSAMPLE = 2.0
"""Sample this many times more windows than the pool keeps, so uncertainty can choose."""


class ConfigMismatchError(ValueError):
    """`--resume` was asked for a directory written by a different configuration."""


@dataclass(frozen=True)
class RoundRecord:
    """One row of `rounds.csv`."""

    round: int
    comparisons: int
    judgements: int
    pairs: int
    pairs_total: int
    label_error_rate: float
    label_error_rate_total: float
    reward_loss: float
    reward_accuracy: float
    reward_val_accuracy: float
    env_steps: int
    true_return_mean: float
    true_return_std: float
    sample_s: float
    feedback_s: float
    reward_s: float
    ppo_s: float
    eval_s: float


@dataclass
class Session:
    """The mutable state of one RLHF run: what a checkpoint saves."""

    cfg: RunConfig
    make_env: EnvFactory
    ensemble: RewardEnsemble
    agent: PPOAgent
    dataset: PreferenceDataset
    records: list[RoundRecord]

    @classmethod
    def create(cls, cfg: RunConfig, out: Path) -> "Session":
        loop = cfg.loop
        make = _env_factory(loop.env)
        probe = make()
        obs_dim, act_dim = observation_dim(probe.observation_space), action_dim(probe.action_space)
        probe.close()
        init_rng = np.random.default_rng(np.random.SeedSequence([loop.seed, 2**20]))
        ensemble = RewardEnsemble(obs_dim, act_dim, cfg.reward, init_rng)
        agent = PPOAgent(
            make, cfg.ppo, seed=loop.seed, reward_fn=ensemble.mean_reward, log_dir=out / "tb"
        )
        dataset = PreferenceDataset.empty(loop.fragment_length, obs_dim, act_dim)
        return cls(cfg, make, ensemble, agent, dataset, [])

    @property
    def next_round(self) -> int:
        return len(self.records)

    def save(self, out: Path) -> None:
        def files(directory: Path) -> None:
            self.agent.save(directory)
            self.ensemble.save(directory / REWARD_FILE)
            self.dataset.save(directory / DATASET_FILE)

        state = {
            "round": self.next_round - 1,
            "records": [dataclasses.asdict(r) for r in self.records],
        }
        write_checkpoint(out, self.next_round - 1, state, files)

    def restore(self, directory: Path, state: dict) -> None:
        self.agent.load(directory)
        self.ensemble.load_state(directory / REWARD_FILE)
        self.dataset = PreferenceDataset.load(directory / DATASET_FILE)
        self.records = [RoundRecord(**row) for row in state["records"]]


def round_rng(seed: int, round_index: int) -> np.random.Generator:
    """The generator of one round, independent of how earlier rounds were run."""
    return np.random.default_rng(np.random.SeedSequence([seed, round_index]))


def build_pool(
    round_index: int,
    make: EnvFactory,
    policy: Policy,
    ensemble: RewardEnsemble,
    size: int,
    cfg: RunConfig,
    rng: np.random.Generator,
) -> BehaviourPool:
    """Sample episodes, tile them into fragments and keep the `size` most uncertain ones."""
    length = cfg.loop.fragment_length
    probe = make()
    horizon = probe.spec.max_episode_steps if probe.spec is not None else None
    probe.close()
    if not horizon or horizon < length:
        raise ValueError(f"env horizon {horizon} is shorter than the fragment length {length}")
    windows = horizon // length
    episodes = max(1, math.ceil(size * POOL_OVERSAMPLE / windows))
    trajectories = sample_trajectories(make, policy, episodes, rng, cfg.loop.exploration_fraction)
    fragments = tile_fragments(trajectories, length)
    obs, acts = stack_fragments(fragments)
    step = ensemble.step_rewards(obs, acts)  # (K, M, L): one forward pass for both uses
    returns = np.ascontiguousarray(step.sum(axis=-1).T)  # (M, K), as ensemble.returns
    keep = most_uncertain(returns.var(axis=1), size)
    return BehaviourPool(
        round_index,
        tuple(fragments[i] for i in keep),
        returns[keep],
        step_variance(step[:, keep]),
    )


def run_round(
    session: Session, oracle: Oracle, n_comparisons: int, steps: int, show_progress: bool
) -> RoundRecord:
    """One full round; appends its record to the session and returns it."""
    cfg, loop = session.cfg, session.cfg.loop
    index = session.next_round
    rng = round_rng(loop.seed, index)
    sample_rng, feedback_rng, pair_rng, fit_rng, ppo_rng = rng.spawn(5)
    timer = _PhaseTimer()

    with timer("sample"):
        pool_size = min(loop.pool_cap, max(2, math.ceil(loop.pool_factor * n_comparisons)))
        pool = build_pool(
            index,
            session.make_env,
            session.agent.policy(),
            session.ensemble,
            pool_size,
            cfg,
            sample_rng,
        )
    with timer("feedback"):
        judgements = oracle.gather(pool, n_comparisons, feedback_rng)
        derive = PAIR_DERIVATIONS[loop.pair_derivation]
        pairs = [pair for j in judgements for pair in derive(j, pair_rng)]
        if loop.pair_cap is not None:
            pairs = cap_pairs(pairs, math.floor(loop.pair_cap * n_comparisons), pair_rng)
        before = len(session.dataset)
        session.dataset.add(pool.fragments, pairs, index)
        round_errors = _label_errors(pool, pairs)
    with timer("reward"):
        multiplier = cfg.reward.initial_epoch_multiplier if index == 0 else 1.0
        epochs = max(1, round(cfg.reward.epochs * multiplier))
        report = fit(session.ensemble, session.dataset, cfg.reward, fit_rng, epochs)
    with timer("ppo"):
        seed = int(ppo_rng.integers(2**31 - 1))
        session.agent.learn(steps, seed, show_progress=show_progress)
    with timer("eval"):
        returns = evaluate(
            session.make_env,
            session.agent.policy(deterministic=True),
            loop.eval_episodes,
            np.random.default_rng(np.random.SeedSequence([loop.seed, 2**21])),
        )
    record = RoundRecord(
        round=index,
        comparisons=n_comparisons,
        judgements=len(judgements),
        pairs=len(session.dataset) - before,
        pairs_total=len(session.dataset),
        label_error_rate=round_errors,
        label_error_rate_total=session.dataset.label_error_rate(),
        reward_loss=report.loss,
        reward_accuracy=report.accuracy,
        reward_val_accuracy=report.validation_accuracy,
        env_steps=session.agent.num_timesteps,
        true_return_mean=float(returns.mean()),
        true_return_std=float(returns.std()),
        **timer.seconds,
    )
    session.records.append(record)
    return record


def run_session(
    cfg: RunConfig,
    out: Path,
    resume: bool = False,
    show_progress: bool = True,
    oracle: Oracle | None = None,
    on_round: Callable[[RoundRecord], None] | None = None,
) -> list[RoundRecord]:
    """Run (or continue, with `resume`) a whole RLHF session, writing results into `out`.

    Writes `config.json`, `rounds.csv` (rewritten after every round), TensorBoard logs and
    one checkpoint per round. Rounds 0 … R−1 gather feedback; when `final_steps` > 0 a last
    row (round R, no comparisons) trains PPO further on the frozen learned reward.
    """
    loop = cfg.loop
    out.mkdir(parents=True, exist_ok=True)
    config_path = out / CONFIG_FILE
    if resume and config_path.exists():
        saved = RunConfig.load(config_path)
        if saved != cfg:
            raise ConfigMismatchError(
                f"{config_path} was written by a different configuration; "
                "use the same options to resume or another --out"
            )
    cfg.save(config_path)

    session = Session.create(cfg, out)
    if resume and (found := latest_checkpoint(out)) is not None:
        directory, state = found
        session.restore(directory, state)
        log.info("resuming %s after round %d", out, state["round"])
    oracle = oracle or ORACLES[loop.oracle](loop)
    schedule = comparisons_per_round(
        loop.comparisons, loop.rounds, loop.initial_fraction, loop.schedule
    )
    plan = [(n, loop.steps // loop.rounds) for n in schedule]
    if loop.final_steps > 0:
        plan.append((0, loop.final_steps))

    bar = tqdm(
        total=len(plan),
        initial=session.next_round,
        desc=loop.env,
        unit="round",
        disable=not show_progress,
    )
    try:
        while session.next_round < len(plan):
            n_comparisons, steps = plan[session.next_round]
            record = run_round(session, oracle, n_comparisons, steps, show_progress)
            session.save(out)
            write_records(out / RESULTS_FILE, session.records)
            log.info(
                "round %d: %d pairs in total, label error %.3f, reward acc %.3f, true return %.2f",
                record.round,
                record.pairs_total,
                record.label_error_rate_total,
                record.reward_accuracy,
                record.true_return_mean,
            )
            bar.update(1)
            bar.set_postfix(true_return=f"{record.true_return_mean:.1f}")
            if on_round is not None:
                on_round(record)
    finally:
        bar.close()
        session.agent.close()
    return session.records


def write_records(path: Path, records: list[RoundRecord]) -> None:
    """Rewrite the per-round CSV atomically."""
    tmp = path.with_suffix(".tmp")
    with tmp.open("w", newline="") as handle:
        writer = csv.DictWriter(
            handle, fieldnames=[f.name for f in dataclasses.fields(RoundRecord)]
        )
        writer.writeheader()
        writer.writerows(dataclasses.asdict(r) for r in records)
    tmp.replace(path)


def _label_errors(pool: BehaviourPool, pairs: list[Pair]) -> float:
    if not pairs:
        return float("nan")
    true = pool.true_returns
    a, b = (np.array([p.a for p in pairs]), np.array([p.b for p in pairs]))
    return float(wrong_labels(true[a], true[b], np.array([p.label for p in pairs])).mean())


def _env_factory(name: str) -> EnvFactory:
    make_env(name).close()  # fail early, with the registry's message, on an unknown env
    return lambda: make_env(name)


class _PhaseTimer:
    """Wall time per named phase: `with timer("ppo"): ...`, then `timer.seconds`."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}

    def __call__(self, phase: str) -> "_PhaseTimer":
        self._phase = phase
        return self

    def __enter__(self) -> None:
        self._start = time.perf_counter()

    def __exit__(self, *exc: object) -> None:
        self.seconds[f"{self._phase}_s"] = time.perf_counter() - self._start
