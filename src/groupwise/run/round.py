"""One round of the RLHF loop (SPEC §3), in two halves with a teacher between them.

    offer = begin_round(run, strategy, budget)       # pool, its tree, the strategy's queries
    judgements = teacher.answer(offer.pool, offer.queries, rng)   # a DM, or a person
    record = end_round(run, offer, judgements)       # pairs → dataset → fit → PPO → eval → commit

`run_round` is exactly that with a simulated teacher. The app's worker runs the halves apart
in time (`groupwise.worker.jobs`): `begin_round` when a round is prepared (its offer
published as clips, tree, suggestions and the pairwise queue), `end_round` on the stored
judgements once the person ends the round. A person and a simulated decision-maker answer
the same queries, and the same function turns their judgements into training.

Randomness: the round's streams (`groupwise.run.streams.round_streams`): the pool from
`sample`, the strategy's queries (and then a simulated teacher) from `feedback`, each
judgement's pairs from its own stream (`preferences.pairs.judgement_pairs`, keyed by its
place in the round), the pair cap from `pairs`, the fit from `fit`, PPO from `ppo`.
"""

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from groupwise.behaviour import BehaviourTree
from groupwise.behaviour.pool import BehaviourPool
from groupwise.config import LoopConfig, RunConfig
from groupwise.pool.sampling import sample_pool
from groupwise.pool.sources import PoolSource, pool_sources
from groupwise.preferences.judgement import Judgement
from groupwise.query.strategies import Query, QueryStrategy
from groupwise.reward import FitReport, fit
from groupwise.rl.rollout import Evaluation, evaluate_episodes
from groupwise.run.pairs import round_pairs
from groupwise.run.progress import RunCallback, as_callback
from groupwise.run.records import PhaseTimer, RoundRecord
from groupwise.run.run import Run
from groupwise.run.streams import RoundStreams, eval_rng, round_streams
from groupwise.teachers.base import Feedback
from groupwise.teachers.calibration import calibrated_noise_sd


@dataclass(frozen=True)
class Offer:
    """What a round offers its teacher: the pool, its behaviour tree and the queries.

    `budget` is the round's comparison budget (what the pair cap and `RoundRecord.comparisons`
    read; 0: no limit, as in an app round); `queries` the strategy's proposals in the order
    to ask them; `candidates` how many group candidates the tree offered (nan for a
    strategy without them); `sample_s` the seconds sampling took.
    """

    pool: BehaviourPool
    tree: BehaviourTree | None
    queries: tuple[Query, ...]
    budget: int
    candidates: float = math.nan
    sample_s: float = 0.0

    @property
    def round(self) -> int:
        return self.pool.round


def pool_size(loop: LoopConfig, budget: int) -> int:
    """N: `loop.pool_size` when set, else pool_factor × the round's comparisons; at least 2,
    at most `pool_cap`."""
    if loop.pool_size is not None:
        return loop.pool_size
    return min(loop.pool_cap, max(2, math.ceil(loop.pool_factor * budget)))


def begin_round(
    run: Run,
    strategy: QueryStrategy,
    budget: int,
    *,
    n_queries: int | None = None,
    streams: RoundStreams | None = None,
    callback: RunCallback | None = None,
    round_index: int | None = None,
    sources: Sequence[PoolSource] | None = None,
) -> Offer:
    """The first half of round `run.next_round` (or of `round_index`: the next round's
    offer, prepared while round `run.next_round` is still open, as continuous training
    does): sample the pool from the round's sources (`pool.sources.pool_sources`: the
    current policy, a share of it from biased variants of the policy when
    `loop.pool_variants` asks for them) (of the `pool_oversample` × N windows those the
    ensemble is most uncertain about, or a random N, `loop.pool_selection`), build its tree,
    and let `strategy` propose `n_queries` (default `budget`) comparisons of it.

    `streams` are the round's (`round_streams`); pass them to continue their `feedback`
    stream with a simulated teacher, as `run_round` does. `sources`: where the pool comes
    from (default `pool_sources(loop)`; continuous training's `pool.recent.fresh_sources`).
    `callback` hears the phases
    "sample" (steps sampled towards the windows) and "dtw" (pairs of behaviours measured).
    """
    loop, callback = run.cfg.loop, as_callback(callback)
    index = run.next_round if round_index is None else round_index
    streams = streams or round_streams(loop.seed, index)
    tick = time.perf_counter()
    pool = sample_pool(
        run.make_env,
        run.agent.policy(),
        pool_size(loop, budget),
        loop.fragment_length,
        streams.sample,
        round_index=index,
        oversample=loop.pool_oversample,
        max_windows=loop.pool_windows_max,
        ensemble=run.ensemble,
        select=loop.pool_selection,
        progress=lambda done, total: callback.on_phase("sample", done, total),
        sources=pool_sources(loop) if sources is None else sources,
        agent=run.agent,
    )
    sample_s = time.perf_counter() - tick
    tree = None
    if len(pool) >= 2:
        pool.measure_distances(  # with the tree's DTW band and time step, as it is built
            lambda done, total: callback.on_phase("dtw", done, total), cfg=run.cfg.tree
        )
        tree = pool.tree(run.cfg.tree)
    wanted = budget if n_queries is None else n_queries
    queries = strategy.propose(pool, wanted, streams.feedback) if wanted > 0 else []
    offered = getattr(strategy, "candidates", None)
    return Offer(
        pool=pool,
        tree=tree,
        queries=tuple(queries),
        budget=budget,
        candidates=float(len(offered(pool))) if callable(offered) else math.nan,
        sample_s=sample_s,
    )


def end_round(
    run: Run,
    offer: Offer,
    judgements: Sequence[Judgement],
    steps: int,
    *,
    keys: Sequence[int] | None = None,
    asked: int | None = None,
    feedback_s: float = 0.0,
    callback: RunCallback | None = None,
) -> RoundRecord:
    """The second half of the round: the judgements' pairs (`round_pairs`) into the
    cumulative dataset, the reward ensemble fitted on it (round 0 with
    `initial_epoch_multiplier` × the epochs), `steps` PPO steps on the learned reward,
    the greedy policy's true return; the record appended and, when
    the run has a directory, committed (checkpoint and ``rounds.csv``).

    `keys` are the judgements' places in the round (default: their places in the list; the
    app's, with undone ones counted); `asked` how many of the offer's queries the teacher
    was asked (None for a person: the query diagnostics stay nan); `feedback_s` the seconds
    the teacher took.
    """
    loop, callback = run.cfg.loop, as_callback(callback)
    index = run.next_round
    if offer.round != index:
        raise ValueError(f"the offer is of round {offer.round}, the run is at round {index}")
    streams = round_streams(loop.seed, index)
    timer = PhaseTimer({"sample_s": offer.sample_s, "feedback_s": feedback_s})
    pairs = round_pairs(judgements, loop, index, offer.budget, streams.pairs, keys)
    run.dataset.add(offer.pool.fragments, pairs, index)
    with timer("reward"):
        callback.on_phase("reward", 0, len(run.dataset))
        multiplier = run.cfg.reward.initial_epoch_multiplier if index == 0 else 1.0
        epochs = max(1, round(run.cfg.reward.epochs * multiplier))
        report = fit(run.ensemble, run.dataset, run.cfg.reward, streams.fit, epochs)
    _learn(run, steps, streams, timer, callback)
    clock_s = math.nan
    if run.cfg.teacher.pace_s is not None and asked is not None:
        pace, rate = run.cfg.teacher.pace_s, run.cfg.training.ppo_steps_per_s
        clock_s = clock_before(run) + asked * pace + steps / rate
    return finish_round(
        run,
        offer,
        judgements,
        report,
        timer,
        callback,
        asked=asked,
        clock_s=clock_s,
    )


def finish_round(
    run: Run,
    offer: Offer,
    judgements: Sequence[Judgement],
    report: FitReport | None,
    timer: PhaseTimer,
    callback: RunCallback,
    *,
    asked: int | None,
    clock_s: float = math.nan,
) -> RoundRecord:
    """Every feedback round's end, once its pairs are in the dataset and the agent trained:
    the greedy policy's true return, the round's record (`report`: the round's last fit,
    None when there was none), appended and committed."""
    evaluation = _evaluate(run, timer, callback)
    this_round = run.dataset.rounds == run.next_round
    record = _record(
        run,
        evaluation,
        timer,
        comparisons=offer.budget,
        judgements=len(judgements),
        pairs=int(this_round.sum()),
        label_error_rate=run.dataset.label_error_rate(this_round),
        label_error_untied=run.dataset.label_error_rate(this_round, untied=True),
        reward_loss=report.loss if report else math.nan,
        reward_accuracy=report.accuracy if report else math.nan,
        reward_val_accuracy=report.validation_accuracy if report else math.nan,
        clock_s=clock_s,
        **_diagnostics(offer, asked, len(judgements), run.cfg),
    )
    return _append(run, record, callback)


def train_frozen(run: Run, steps: int, *, callback: RunCallback | None = None) -> RoundRecord:
    """Round `run.next_round` without feedback: `steps` PPO steps on the frozen learned
    reward, then the true return; appended and committed as `end_round` does. Its PPO seed
    comes from the round's PPO stream, as a feedback round's does."""
    callback = as_callback(callback)
    streams = round_streams(run.cfg.loop.seed, run.next_round)
    timer = PhaseTimer({"sample_s": 0.0, "feedback_s": 0.0, "reward_s": 0.0})
    _learn(run, steps, streams, timer, callback)
    evaluation = _evaluate(run, timer, callback)
    timed = run.cfg.teacher.pace_s is not None
    record = _record(
        run,
        evaluation,
        timer,
        clock_s=clock_before(run) + steps / run.cfg.training.ppo_steps_per_s if timed else math.nan,
        comparisons=0,
        judgements=0,
        pairs=0,
        label_error_rate=math.nan,
        reward_loss=math.nan,
        reward_accuracy=math.nan,
        reward_val_accuracy=math.nan,
    )
    return _append(run, record, callback)


def run_round(
    run: Run, feedback: Feedback, budget: int, steps: int, callback: RunCallback | None = None
) -> RoundRecord:
    """One whole round answered by a simulated teacher: `begin_round` → the teacher answers
    the offer's queries (from the round's feedback stream, after the strategy) → `end_round`."""
    streams = round_streams(run.cfg.loop.seed, run.next_round)
    offer = begin_round(run, feedback.queries, budget, streams=streams, callback=callback)
    tick = time.perf_counter()
    judgements: list[Judgement] = []
    if offer.queries:
        judgements = feedback.teacher.answer(offer.pool, offer.queries, streams.feedback)
    feedback_s = time.perf_counter() - tick
    return end_round(
        run,
        offer,
        judgements,
        steps,
        asked=len(offer.queries),
        feedback_s=feedback_s,
        callback=callback,
    )


def clock_before(run: Run) -> float:
    """A timed teacher's virtual clock when round `run.next_round` begins (0 for the first;
    `groupwise.run.continuous`)."""
    previous = run.records[-1].clock_s if run.records else 0.0
    return 0.0 if math.isnan(previous) else previous


def _learn(
    run: Run, steps: int, streams: RoundStreams, timer: PhaseTimer, callback: RunCallback
) -> None:
    """Train the agent `steps` PPO steps, seeded from the round's PPO stream."""
    with timer("ppo"):
        run.agent.learn(
            steps,
            int(streams.ppo.integers(2**31 - 1)),
            report=lambda done, total: callback.on_phase("ppo", done, total),
        )


def _evaluate(run: Run, timer: PhaseTimer, callback: RunCallback) -> Evaluation:
    """The greedy policy's true returns and, in a target env, its episode scores over
    `eval_episodes` (nan when 0)."""
    loop = run.cfg.loop
    with timer("eval"):
        if loop.eval_episodes == 0:
            return Evaluation(returns=np.full(1, np.nan), scores=np.full(1, np.nan))
        callback.on_phase("eval", 0, loop.eval_episodes)
        return evaluate_episodes(
            run.make_env,
            run.agent.policy(deterministic=True),
            loop.eval_episodes,
            eval_rng(loop.seed),
        )


def _record(run: Run, evaluation: Evaluation, timer: PhaseTimer, **fields: Any) -> RoundRecord:
    """Round `run.next_round`'s record: `fields` of the round, the rest from the run now."""
    values: dict[str, Any] = {**timer.seconds, **fields}
    return RoundRecord(
        round=run.next_round,
        pairs_total=len(run.dataset),
        label_error_rate_total=run.dataset.label_error_rate(),
        env_steps=run.agent.num_timesteps,
        true_return_mean=float(evaluation.returns.mean()),
        true_return_std=float(evaluation.returns.std()),
        target_score_mean=float(evaluation.scores.mean()),
        target_score_std=float(evaluation.scores.std()),
        **values,
    )


def _append(run: Run, record: RoundRecord, callback: RunCallback) -> RoundRecord:
    run.records.append(record)
    if run.out is not None:
        callback.on_phase("checkpoint", 0, 1)
        run.commit()
    callback.on_round_end(record)
    return record


def _diagnostics(
    offer: Offer, asked: int | None, judgements: int, cfg: RunConfig
) -> dict[str, float]:
    """The round's query diagnostics (SPEC §7) for its record; nan where a person answered.
    The noise is the simulated teacher's per behaviour: L·σ, or the calibrated teacher's."""
    returns = offer.pool.true_returns
    noise_sd = cfg.loop.fragment_length * cfg.teacher.noise_sigma
    if cfg.teacher.label_error is not None:
        noise_sd = calibrated_noise_sd(returns, cfg.teacher.label_error)
    sd = float(returns.std()) if len(offer.pool) else math.nan
    diagnostics = {
        "candidates": offer.candidates,
        "return_sd_over_noise": sd / noise_sd if noise_sd > 0 else math.inf,
    }
    if asked is None:
        return diagnostics
    return {
        "queries_asked": float(asked),
        "queries_unused": float(max(offer.budget - asked, 0)),
        "queries_skipped": float(max(asked - judgements, 0)),
        **diagnostics,
    }
