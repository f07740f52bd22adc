"""Queries mixed between behaviours the preference data covers and ones it does not (issue 41).

After PPE (NeurIPS 2025): ensemble disagreement did not flag out-of-distribution states
in PPE's test, so coverage is measured against the preference buffer itself. A behaviour's
coverage score is its distance to the nearest behaviour the teacher has judged so far (every
fragment of the cumulative dataset): in the reward model's input space, [obs ; act] per
step, standardised per dimension over the buffer's and the pool's steps, averaged over the
behaviour's steps,

    c(f) = min over judged g of ‖φ(f) − φ(g)‖₂,   φ(f) = mean over t of z([obs_t ; act_t])

A query's score is the mean c of its behaviours (both groups). PPE asks half its queries
among covered and half among uncovered segments; here a share `share` of a round's queries
is chosen that way, half with the lowest scores and half (the odd one too) with the
highest, from a longer list of the strategy's own proposals, and the rest are the
strategy's first proposals as it ranks them. Being a wrapper around any `QueryStrategy`, it
serves the Groupwise-DM's group suggestions (ranked by `GroupSuggestions`) and the pairwise
queries alike, and `begin_round` composes it (`with_coverage`) only when asked.
"""

from dataclasses import dataclass

import numpy as np

from groupwise.behaviour.pool import BehaviourPool
from groupwise.preferences.dataset import PreferenceDataset
from groupwise.query.strategies import Query, QueryStrategy
from groupwise.types import FloatArray

CANDIDATES_PER_QUERY = 4
"""The strategy proposes this many times the round's queries for the coverage to choose from."""
_SD_FLOOR = 1e-8
"""A dimension constant over every step is not scaled (its z is 0 everywhere)."""


def behaviour_features(
    obs: FloatArray, acts: FloatArray, mean: FloatArray, sd: FloatArray
) -> FloatArray:
    """(N, D) φ: each behaviour's mean over its steps of (x − mean) / sd, x = [obs ; act]
    per step; obs (N, L, obs_dim), acts (N, L, act_dim), mean and sd (D,)."""
    x = np.concatenate([obs, acts], axis=-1).astype(np.float64)
    return np.asarray(((x - mean) / sd).mean(axis=1))


def coverage_scores(
    obs: FloatArray, acts: FloatArray, judged_obs: FloatArray, judged_acts: FloatArray
) -> FloatArray:
    """(N,) c(f) of the behaviours obs (N, L, obs_dim), acts (N, L, act_dim) against the
    judged ones (J, L', ...) (module docstring); all nan when nothing was judged.

    Raises:
        ValueError: the two sets' feature widths differ.
    """
    width = obs.shape[-1] + acts.shape[-1]
    if judged_obs.shape[-1] + judged_acts.shape[-1] != width:
        raise ValueError(
            f"behaviours have {width} features per step, the judged ones "
            f"{judged_obs.shape[-1] + judged_acts.shape[-1]}"
        )
    if len(judged_obs) == 0:
        return np.full(len(obs), np.nan)
    steps = np.concatenate(
        [
            np.concatenate([obs, acts], axis=-1).reshape(-1, width),
            np.concatenate([judged_obs, judged_acts], axis=-1).reshape(-1, width),
        ]
    ).astype(np.float64)
    mean, sd = steps.mean(axis=0), np.maximum(steps.std(axis=0), _SD_FLOOR)
    mine = behaviour_features(obs, acts, mean, sd)
    judged = behaviour_features(judged_obs, judged_acts, mean, sd)
    distances = np.sqrt(((mine[:, None, :] - judged[None, :, :]) ** 2).sum(axis=-1))
    return np.asarray(distances.min(axis=1))


def mixed_order(scores: FloatArray, n_queries: int, share: float) -> list[int]:
    """Which of the candidate queries (scores (C,), in the strategy's order) to ask, in
    order: the first n − m candidates, then of the others the ⌈m/2⌉ with the highest
    scores and the ⌊m/2⌋ with the lowest, m = round(share · n); fewer when there are fewer
    candidates. Ties keep the strategy's order."""
    n = min(n_queries, len(scores))
    by_coverage = round(share * n)
    head = list(range(n - by_coverage))
    rest = np.arange(n - by_coverage, len(scores))
    order = rest[np.argsort(scores[rest], kind="stable")]
    high = [int(i) for i in order[::-1][: by_coverage - by_coverage // 2]]
    taken = set(high)
    low = [int(i) for i in order if int(i) not in taken][: by_coverage // 2]
    return head + high + low


@dataclass(frozen=True, eq=False)
class CoverageMix:
    """`inner`'s queries with a share `share` chosen by coverage of `judged` (module
    docstring). `judged` is read when proposing: the run's cumulative dataset."""

    inner: QueryStrategy
    share: float
    judged: PreferenceDataset

    def __post_init__(self) -> None:
        if not 0.0 <= self.share <= 1.0:
            raise ValueError(f"a coverage share is in [0, 1], got {self.share}")

    def propose(self, pool: BehaviourPool, n_queries: int, rng: np.random.Generator) -> list[Query]:
        if self.judged.n_fragments == 0 or n_queries <= 0 or len(pool) < 2:
            return self.inner.propose(pool, n_queries, rng)
        candidates = self.inner.propose(pool, CANDIDATES_PER_QUERY * n_queries, rng)
        obs = np.stack([f.obs for f in pool.fragments])
        acts = np.stack([f.acts for f in pool.fragments])
        per_behaviour = coverage_scores(obs, acts, self.judged.obs, self.judged.acts)
        scores = np.array([per_behaviour[[*q.left, *q.right]].mean() for q in candidates])
        return [candidates[i] for i in mixed_order(scores, n_queries, self.share)]

    def __getattr__(self, name: str) -> object:  # the strategy's `candidates`, if it has them
        if name == "inner":  # not set yet (a copy being built): no recursion
            raise AttributeError(name)
        return getattr(self.inner, name)


def with_coverage(
    strategy: QueryStrategy, share: float, judged: PreferenceDataset
) -> QueryStrategy:
    """`strategy` itself when `share` is 0, else `CoverageMix(strategy, share, judged)`."""
    return strategy if share == 0 else CoverageMix(strategy, share, judged)
