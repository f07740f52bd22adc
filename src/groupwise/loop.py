"""The RLHF loop (SPEC §3), readable top to bottom.

Per round (`run_round`): sample a pool from the current policy (`sample_pool`) → gather
comparisons (a query strategy proposes, a teacher answers: `oracles.Feedback`) → derive
preference pairs (`derive_pairs`, `limit_pairs`) → `train_round`: fit the reward ensemble on
the cumulative dataset → train the agent on the learned reward → evaluate on the true reward
→ checkpoint. The interactive app runs the same phases apart in time (`server/jobs.py`:
`sample_pool` when a round is prepared, `train_round` once a person ends it), and
`comparisons.PreferenceComparisons` runs `run_round` over a user's own env and agent.
Every round draws its randomness from a generator derived from (seed, round), so a session
resumed from a checkpoint repeats exactly what an uninterrupted one does.
"""

import csv
import dataclasses
import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np
from tqdm.auto import tqdm

from groupwise import sampling
from groupwise.checkpoint import (
    DATASET_FILE,
    REWARD_FILE,
    latest_checkpoint,
    write_checkpoint,
)
from groupwise.config import LoopConfig, RunConfig
from groupwise.envs import make_env
from groupwise.oracles import ORACLES, Feedback, Oracle
from groupwise.pool import BehaviourPool
from groupwise.preferences.dataset import PreferenceDataset
from groupwise.preferences.judgement import Judgement
from groupwise.preferences.pairs import PAIR_DERIVATIONS, Pair, cap_pairs, oversample_pairs
from groupwise.query.schedule import comparisons_per_round
from groupwise.reward import RewardEnsemble, fit
from groupwise.rl.agents import Agent
from groupwise.rl.ppo import PPOAgent
from groupwise.rl.rollout import EnvFactory, evaluate

log = logging.getLogger(__name__)

CONFIG_FILE = "config.json"
RESULTS_FILE = "rounds.csv"


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
    # how the round's feedback went (SPEC §7 diagnostics); nan where unknown (a person)
    queries_asked: float = math.nan
    """Queries the strategy proposed and the teacher was asked."""
    queries_unused: float = math.nan
    """The round's queries the strategy had nothing to propose for."""
    queries_skipped: float = math.nan
    """Asked queries that yielded no judgement (interference, a skipping teacher)."""
    candidates: float = math.nan
    """Group candidates the tree offered (nan for pairwise strategies)."""
    return_sd_over_noise: float = math.nan
    """sd of the pool's true returns ÷ the per-behaviour noise sd L·σ: below about 1 the
    labels are near coin flips whatever the strategy (the information limit)."""


@dataclass
class Session:
    """The mutable state of one RLHF run: what a checkpoint saves.

    `Session.create` wires our own PPO (`groupwise train`, the study, the app); a user's
    own env factory and agent come in through `groupwise.comparisons.PreferenceComparisons`.
    """

    cfg: RunConfig
    make_env: EnvFactory
    ensemble: RewardEnsemble
    agent: Agent
    dataset: PreferenceDataset
    records: list[RoundRecord]

    @classmethod
    def create(cls, cfg: RunConfig, out: Path | None) -> "Session":
        loop = cfg.loop
        make = _env_factory(loop.env)
        ensemble = RewardEnsemble.for_env(make, cfg.reward, init_rng(loop.seed))
        agent = PPOAgent(
            make,
            cfg.ppo,
            seed=loop.seed,
            reward_fn=ensemble.mean_reward,
            log_dir=None if out is None else out / "tb",
        )
        return cls.of(cfg, make, ensemble, agent)

    @classmethod
    def of(
        cls, cfg: RunConfig, make: EnvFactory, ensemble: RewardEnsemble, agent: Agent
    ) -> "Session":
        """A fresh session over given parts (no feedback yet)."""
        dataset = PreferenceDataset.empty(
            cfg.loop.fragment_length, ensemble.obs_dim, ensemble.act_dim
        )
        return cls(cfg, make, ensemble, agent, dataset, [])

    @property
    def next_round(self) -> int:
        return len(self.records)

    @property
    def ppo(self) -> PPOAgent:
        if not isinstance(self.agent, PPOAgent):
            raise TypeError("checkpoints need groupwise's own PPOAgent")
        return self.agent

    def save(self, out: Path) -> None:
        def files(directory: Path) -> None:
            self.ppo.save(directory)
            self.ensemble.save(directory / REWARD_FILE)
            self.dataset.save(directory / DATASET_FILE)

        state = {
            "round": self.next_round - 1,
            "records": [dataclasses.asdict(r) for r in self.records],
        }
        write_checkpoint(out, self.next_round - 1, state, files)

    def restore(self, directory: Path, state: dict) -> None:
        self.ppo.load(directory)
        self.ensemble.load_state(directory / REWARD_FILE)
        self.dataset = PreferenceDataset.load(directory / DATASET_FILE)
        self.records = [RoundRecord(**row) for row in state["records"]]


def init_rng(seed: int) -> np.random.Generator:
    """The generator of the reward ensemble's initial weights."""
    return np.random.default_rng(np.random.SeedSequence([seed, 2**20]))


def round_rng(seed: int, round_index: int) -> np.random.Generator:
    """The generator of one round, independent of how earlier rounds were run."""
    return np.random.default_rng(np.random.SeedSequence([seed, round_index]))


class RoundStreams(NamedTuple):
    """A round's independent random streams, one per phase (the app runs them apart)."""

    sample: np.random.Generator
    feedback: np.random.Generator
    pairs: np.random.Generator
    fit: np.random.Generator
    ppo: np.random.Generator


def round_streams(seed: int, round_index: int) -> RoundStreams:
    return RoundStreams(*round_rng(seed, round_index).spawn(5))


def eval_rng(seed: int) -> np.random.Generator:
    """The evaluation's generator: the same reset seeds after every round."""
    return np.random.default_rng(np.random.SeedSequence([seed, 2**21]))


def pool_size(loop: LoopConfig, n_comparisons: int) -> int:
    """N = pool_factor × the round's comparisons, at least 2, at most `pool_cap`."""
    return min(loop.pool_cap, max(2, math.ceil(loop.pool_factor * n_comparisons)))


def sample_pool(
    session: Session,
    round_index: int,
    size: int,
    rng: np.random.Generator,
) -> BehaviourPool:
    """The round's pool from the current policy: the `size` of `loop.pool_oversample` ×
    `size` windows the ensemble is most uncertain about, or a random `size` of them
    (`loop.pool_selection`; `sampling.sample_pool`)."""
    loop = session.cfg.loop
    return sampling.sample_pool(
        session.make_env,
        session.agent.policy(),
        size,
        loop.fragment_length,
        rng,
        round_index=round_index,
        exploration_fraction=loop.exploration_fraction,
        oversample=loop.pool_oversample,
        ensemble=session.ensemble,
        select=loop.pool_selection,
    )


def derive_pairs(
    judgements: list[Judgement], loop: LoopConfig, rng: np.random.Generator
) -> list[Pair]:
    """Each judgement's preference pairs by `loop.pair_derivation` (SPEC §6), times
    `loop.pair_oversample` (`oversample_pairs`; 1, the default, draws exactly those)."""
    derive = PAIR_DERIVATIONS[loop.pair_derivation]
    factor = loop.pair_oversample
    return [pair for j in judgements for pair in oversample_pairs(j, derive, factor, rng)]


def limit_pairs(
    pairs: list[Pair], loop: LoopConfig, n_comparisons: int, rng: np.random.Generator
) -> list[Pair]:
    """A round's pairs, capped at ⌊pair_cap × comparisons⌋ when `loop.pair_cap` is set."""
    if loop.pair_cap is None:
        return pairs
    return cap_pairs(pairs, math.floor(loop.pair_cap * n_comparisons), rng)


def train_round(
    session: Session,
    round_index: int,
    *,
    comparisons: int,
    judgements: int,
    steps: int,
    streams: RoundStreams,
    seconds: dict[str, float],
    feedback: dict[str, float] | None = None,
    show_progress: bool = False,
    report: Callable[[str, int, int], None] | None = None,
) -> RoundRecord:
    """The second half of every round, headless or in the app: fit the reward ensemble on
    the session's dataset (round 0 with `initial_epoch_multiplier` × the epochs), train the
    agent for `steps` on the learned reward, evaluate it on the true reward, and append the
    round's record. `seconds` holds the sample and feedback phases' wall times; `report`
    hears ("reward" | "ppo" | "eval", done, total); `feedback` the round's query diagnostics
    (`feedback_diagnostics`)."""
    cfg = session.cfg
    timer = _PhaseTimer(seconds)

    def tell(phase: str, done: int, total: int) -> None:
        if report is not None:
            report(phase, done, total)

    with timer("reward"):
        tell("reward", 0, len(session.dataset))
        multiplier = cfg.reward.initial_epoch_multiplier if round_index == 0 else 1.0
        epochs = max(1, round(cfg.reward.epochs * multiplier))
        fit_report = fit(session.ensemble, session.dataset, cfg.reward, streams.fit, epochs)
    returns = _learn_and_evaluate(session, steps, streams.ppo, timer, report, show_progress)
    dataset = session.dataset
    this_round = dataset.rounds == round_index
    record = RoundRecord(
        round=round_index,
        comparisons=comparisons,
        judgements=judgements,
        pairs=int(this_round.sum()),
        pairs_total=len(dataset),
        label_error_rate=dataset.label_error_rate(this_round),
        label_error_rate_total=dataset.label_error_rate(),
        reward_loss=fit_report.loss,
        reward_accuracy=fit_report.accuracy,
        reward_val_accuracy=fit_report.validation_accuracy,
        env_steps=session.agent.num_timesteps,
        true_return_mean=float(returns.mean()),
        true_return_std=float(returns.std()),
        **timer.seconds,
        **(feedback or {}),
    )
    session.records.append(record)
    return record


def _learn_and_evaluate(
    session: Session,
    steps: int,
    ppo_rng: np.random.Generator,
    timer: "_PhaseTimer",
    report: Callable[[str, int, int], None] | None,
    show_progress: bool,
) -> np.ndarray:
    """Train the agent `steps` PPO steps (seeded from the round's PPO stream), then its
    greedy policy's true returns over `eval_episodes` (nan when 0): every round's end."""
    loop = session.cfg.loop
    with timer("ppo"):
        session.agent.learn(
            steps,
            int(ppo_rng.integers(2**31 - 1)),
            show_progress=show_progress,
            report=None if report is None else lambda done, total: report("ppo", done, total),
        )
    with timer("eval"):
        if loop.eval_episodes == 0:
            return np.full(1, np.nan)
        if report is not None:
            report("eval", 0, loop.eval_episodes)
        return evaluate(
            session.make_env,
            session.agent.policy(deterministic=True),
            loop.eval_episodes,
            eval_rng(loop.seed),
        )


def train_frozen(
    session: Session,
    round_index: int,
    steps: int,
    *,
    show_progress: bool = False,
    report: Callable[[str, int, int], None] | None = None,
) -> RoundRecord:
    """Round `round_index` without feedback: `steps` PPO steps on the frozen learned reward,
    then the true return over `eval_episodes`; appends and returns its record. Its PPO seed
    comes from the round's PPO stream (`loop.round_streams`), as a feedback round's does."""
    timer = _PhaseTimer({"sample_s": 0.0, "feedback_s": 0.0, "reward_s": 0.0})
    ppo_rng = round_streams(session.cfg.loop.seed, round_index).ppo
    returns = _learn_and_evaluate(session, steps, ppo_rng, timer, report, show_progress)
    dataset = session.dataset
    record = RoundRecord(
        round=round_index,
        comparisons=0,
        judgements=0,
        pairs=0,
        pairs_total=len(dataset),
        label_error_rate=math.nan,
        label_error_rate_total=dataset.label_error_rate(),
        reward_loss=math.nan,
        reward_accuracy=math.nan,
        reward_val_accuracy=math.nan,
        env_steps=session.agent.num_timesteps,
        true_return_mean=float(returns.mean()),
        true_return_std=float(returns.std()),
        **timer.seconds,
    )
    session.records.append(record)
    return record


def feedback_diagnostics(
    oracle: Oracle,
    pool: BehaviourPool,
    n_comparisons: int,
    asked: int,
    judgements: int,
    noise_sd: float,
) -> dict[str, float]:
    """The round's query diagnostics for its `RoundRecord` (`noise_sd` = L·σ)."""
    strategy = getattr(oracle, "queries", None)
    offered = getattr(strategy, "candidates", None)
    sd = float(pool.true_returns.std()) if len(pool) else math.nan
    return {
        "queries_asked": float(asked),
        "queries_unused": float(max(n_comparisons - asked, 0)),
        "queries_skipped": float(max(asked - judgements, 0)),
        "candidates": float(len(offered(pool))) if callable(offered) else math.nan,
        "return_sd_over_noise": sd / noise_sd if noise_sd > 0 else math.inf,
    }


def run_round(
    session: Session, oracle: Oracle, n_comparisons: int, steps: int, show_progress: bool
) -> RoundRecord:
    """One full round: sample → pool → feedback → pairs → `train_round`."""
    loop = session.cfg.loop
    index = session.next_round
    streams = round_streams(loop.seed, index)
    timer = _PhaseTimer()
    with timer("sample"):
        pool = sample_pool(session, index, pool_size(loop, n_comparisons), streams.sample)
    with timer("feedback"):
        if isinstance(oracle, Feedback):
            queries, judgements = oracle.ask(pool, n_comparisons, streams.feedback)
            asked = len(queries)
        else:
            judgements = oracle.gather(pool, n_comparisons, streams.feedback)
            asked = n_comparisons
        pairs = derive_pairs(judgements, loop, streams.pairs)
        pairs = limit_pairs(pairs, loop, n_comparisons, streams.pairs)
        session.dataset.add(pool.fragments, pairs, index)
    return train_round(
        session,
        index,
        comparisons=n_comparisons,
        judgements=len(judgements),
        steps=steps,
        streams=streams,
        seconds=timer.seconds,
        feedback=feedback_diagnostics(
            oracle,
            pool,
            n_comparisons,
            asked,
            len(judgements),
            loop.fragment_length * loop.noise_sigma,
        ),
        show_progress=show_progress,
    )


def round_plan(loop: LoopConfig) -> list[tuple[int, int]]:
    """(comparisons, PPO steps) of each round; a last (0, final_steps) row when set."""
    schedule = comparisons_per_round(
        loop.comparisons, loop.rounds, loop.initial_fraction, loop.schedule
    )
    plan = [(n, loop.steps // loop.rounds) for n in schedule]
    if loop.final_steps > 0:
        plan.append((0, loop.final_steps))
    return plan


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
    if oracle is None:
        if loop.oracle not in ORACLES:
            raise ValueError(
                f"no simulated decision-maker {loop.oracle!r} (a person answers an app "
                f"session's rounds); choose from {', '.join(ORACLES)}"
            )
        oracle = ORACLES[loop.oracle](loop)

    def finished(record: RoundRecord) -> None:
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
        if on_round is not None:
            on_round(record)

    try:
        run_rounds(session, oracle, show_progress, finished)
    finally:
        session.ppo.close()
    return session.records


def run_rounds(
    session: Session,
    oracle: Oracle,
    show_progress: bool = False,
    on_round: Callable[[RoundRecord], None] | None = None,
) -> list[RoundRecord]:
    """Run the session's rounds not run yet (`round_plan`), calling `on_round` after each;
    the one round driver of `run_session` and `PreferenceComparisons.train`."""
    plan = round_plan(session.cfg.loop)
    bar = tqdm(
        total=len(plan),
        initial=session.next_round,
        desc=session.cfg.loop.env,
        unit="round",
        disable=not show_progress,
    )
    with bar:
        while session.next_round < len(plan):
            n_comparisons, steps = plan[session.next_round]
            if n_comparisons == 0:  # the final row: PPO on the frozen reward
                record = train_frozen(
                    session, session.next_round, steps, show_progress=show_progress
                )
            else:
                record = run_round(session, oracle, n_comparisons, steps, show_progress)
            bar.update(1)
            bar.set_postfix(true_return=f"{record.true_return_mean:.1f}")
            if on_round is not None:
                on_round(record)
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


def _env_factory(name: str) -> EnvFactory:
    make_env(name).close()  # fail early, with the registry's message, on an unknown env
    return lambda: make_env(name)


class _PhaseTimer:
    """Wall time per named phase: `with timer("ppo"): ...`, then `timer.seconds`."""

    def __init__(self, seconds: dict[str, float] | None = None) -> None:
        self.seconds: dict[str, float] = dict(seconds or {})

    def __call__(self, phase: str) -> "_PhaseTimer":
        self._phase = phase
        return self

    def __enter__(self) -> None:
        self._start = time.perf_counter()

    def __exit__(self, *exc: object) -> None:
        self.seconds[f"{self._phase}_s"] = time.perf_counter() - self._start
