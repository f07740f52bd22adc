"""How a simulated decision-maker answers one query (SPEC §7).

A query is two groups of pool indices (a pairwise query is two groups of one). A
`SimulatedTeacher` answers it in two steps:

1. perception (`Perception`): each behaviour's return as the DM sees it, true return plus
   ε ~ Normal(0, (L·σ)²) drawn once per behaviour per judgement (paper eq. 1); a myopic
   teacher discounts earlier steps first (`gamma`, B-Pref);
2. labelling: a pipeline of steps, each a function `(LabelState, rng) -> LabelState` that
   may decide, skip or change the answer. `decide` is the group decision below; the imperfect
   teachers of `imperfect.py` add steps before it (skip, equal) or after it (mistake).

The group decision (both group DMs; paper §6: "the group whose behaviours' rewards had a
higher mean, including ε, was considered the preferred one. In the event of significant
interference ... comparison was skipped"):
- the group with the higher mean perceived return wins; b = midpoint of the two means;
- a member is on the wrong side of b when it is a winner at or below b, or a loser at or
  above b (a member exactly at b is no better than the midpoint, so it counts as wrong:
  then a noise-free DM never labels a pair of equal returns as a strict preference);
- if more than half of either group is on the wrong side the query is skipped
  ("significant interference"); otherwise the wrong-side members are removed (the user
  removing outliers) and the rest is judged;
- exactly equal means: there is no winner and no wrong side. If every member of both groups
  is perceived exactly at b (for a pair: two equal returns) the answer is "equal" (0.5),
  as the pairwise DM answers an exact tie; otherwise the query is skipped, because "equal"
  on groups whose members differ would label every differing pair wrongly.
For two groups of one the decision is simply "the higher perceived return wins".
"""

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from groupwise.behaviour.pool import BehaviourPool
from groupwise.preferences.judgement import EQUAL, LEFT_BETTER, RIGHT_BETTER, Judgement, Source
from groupwise.query.strategies import Query
from groupwise.teachers.noise import perceived_returns
from groupwise.types import FloatArray


@dataclass(frozen=True)
class GroupDecision:
    """The outcome of a group decision: the members kept on each side and the label."""

    left: tuple[int, ...]
    right: tuple[int, ...]
    label: float
    removed: int  # members removed as outliers


def group_decision(
    left: Sequence[int],
    right: Sequence[int],
    seen_left: FloatArray,
    seen_right: FloatArray,
) -> GroupDecision | None:
    """The group decision (module docstring) on perceived returns; None when skipped.

    left, right: pool indices (m,), (n,); seen_left, seen_right: their perceived returns.
    """
    a, b = np.asarray(seen_left, dtype=np.float64), np.asarray(seen_right, dtype=np.float64)
    if a.shape != (len(left),) or b.shape != (len(right),) or not len(left) or not len(right):
        raise ValueError("each group needs one perceived return per member, and a member")
    mean_a, mean_b = float(a.mean()), float(b.mean())
    mid = (mean_a + mean_b) / 2
    if mean_a == mean_b:
        if (a == mid).all() and (b == mid).all():
            return GroupDecision(tuple(left), tuple(right), EQUAL, 0)
        return None
    left_wins = mean_a > mean_b
    wrong_a = a <= mid if left_wins else a >= mid
    wrong_b = b >= mid if left_wins else b <= mid
    if wrong_a.sum() > len(a) / 2 or wrong_b.sum() > len(b) / 2:
        return None
    return GroupDecision(
        left=tuple(int(i) for i, w in zip(left, wrong_a, strict=True) if not w),
        right=tuple(int(i) for i, w in zip(right, wrong_b, strict=True) if not w),
        label=LEFT_BETTER if left_wins else RIGHT_BETTER,
        removed=int(wrong_a.sum() + wrong_b.sum()),
    )


@dataclass(frozen=True)
class Perception:
    """How a DM sees returns: Σ_t γ^(L−1−t) r_t + ε, ε ~ Normal(0, (L·σ)²) (paper eq. 1).

    `sigma` is the noise per step (SPEC §7, default 0.25). `gamma` < 1 is B-Pref's myopic
    teacher, who weighs the last step fully and earlier steps less; 1 sees the true return.
    """

    sigma: float = 0.25
    gamma: float = 1.0

    def __post_init__(self) -> None:
        if self.sigma < 0:
            raise ValueError(f"noise sigma must be >= 0, got {self.sigma}")
        if not 0.0 < self.gamma <= 1.0:
            raise ValueError(f"myopic discount must be in (0, 1], got {self.gamma}")

    def __call__(
        self, pool: BehaviourPool, indices: Sequence[int], rng: np.random.Generator
    ) -> FloatArray:
        """(n,) perceived returns of pool behaviours `indices`, fresh noise for each."""
        idx = np.asarray(indices, dtype=np.int64)
        if self.gamma == 1.0:
            returns = pool.true_returns[idx]
        else:
            returns = np.array(
                [_discounted(pool.fragments[i].true_rewards, self.gamma) for i in idx]
            )
        length = pool.fragments[int(idx[0])].length if idx.size else 0
        return perceived_returns(returns, length, self.sigma, rng)


def _discounted(rewards: FloatArray, gamma: float) -> float:
    r = np.asarray(rewards, dtype=np.float64)
    return float((gamma ** np.arange(len(r) - 1, -1, -1) * r).sum())


@dataclass(frozen=True)
class LabelState:
    """The state a teacher's labelling steps pass along.

    `left`/`right` are the members still in each group, `seen_*` their perceived returns
    (same order); `label` is None until a step decides, `skipped` ends the pipeline.
    `pool_returns` (N,) are the pool's true returns, the teacher's sense of scale for
    thresholds.
    """

    left: tuple[int, ...]
    right: tuple[int, ...]
    seen_left: FloatArray  # (m,)
    seen_right: FloatArray  # (n,)
    pool_returns: FloatArray  # (N,)
    label: float | None = None
    skipped: bool = False
    removed: int = 0


Step = Callable[[LabelState, np.random.Generator], LabelState]
"""One labelling step: returns the query decided, skipped or changed (or as it was)."""


def decide(query: LabelState, rng: np.random.Generator) -> LabelState:
    """The group decision as a labelling step; leaves an already decided query alone."""
    del rng
    if query.label is not None or query.skipped:
        return query
    outcome = group_decision(query.left, query.right, query.seen_left, query.seen_right)
    if outcome is None:
        return replace(query, skipped=True)
    keep_l = np.isin(query.left, outcome.left)
    keep_r = np.isin(query.right, outcome.right)
    return replace(
        query,
        left=outcome.left,
        right=outcome.right,
        seen_left=query.seen_left[keep_l],
        seen_right=query.seen_right[keep_r],
        label=outcome.label,
        removed=query.removed + outcome.removed,
    )


@dataclass(frozen=True)
class SimulatedTeacher:
    """A simulated DM's answer to one query: `perception`, then the labelling `steps`.

    The default is the paper's DM: noisy perception and the group decision.
    """

    perception: Perception = Perception()
    steps: tuple[Step, ...] = (decide,)

    def judge(
        self,
        pool: BehaviourPool,
        left: Sequence[int],
        right: Sequence[int],
        rng: np.random.Generator,
        source: Source = Source.SIMULATED,
    ) -> Judgement | None:
        """The judgement of `left` vs `right` (pool indices), or None when skipped.

        The judgement keeps only the members that survived outlier removal; `edits`
        counts the removed ones.
        """
        left, right = tuple(int(i) for i in left), tuple(int(i) for i in right)
        seen = self.perception(pool, left + right, rng)
        query = LabelState(left, right, seen[: len(left)], seen[len(left) :], pool.true_returns)
        for step in self.steps:
            query = step(query, rng)
            if query.skipped:
                return None
        if query.label is None:
            raise ValueError("the teacher's steps left the query undecided (missing `decide`)")
        return Judgement(query.left, query.right, query.label, source, edits=query.removed)

    def answer(
        self, pool: BehaviourPool, queries: Sequence[Query], rng: np.random.Generator
    ) -> list[Judgement]:
        """The judgements of `queries`, in order; a skipped query yields none."""
        judgements = (self.judge(pool, q.left, q.right, rng) for q in queries)
        return [j for j in judgements if j is not None]
