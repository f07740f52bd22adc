"""Query strategies: which comparisons to ask of a pool (SPEC §5, §7), apart from who answers.

A strategy *proposes* queries, a teacher (`groupwise.teachers.Teacher`: a simulated
decision-maker, an imperfect teacher, or a person through the web page) *answers* them.
`groupwise.teachers.Feedback` puts one of each together into what the loop asks for
feedback. The three strategies of the paper's study:

- `PairwiseQueries`: pairwise active learning, for each query the most disputed of
  `candidates` random pairs (the Pairwise-DM's and the app's pairwise mode);
- `GroupSuggestions`: the group-variance suggestions over the behaviour tree's candidate
  groups (the Groupwise-DM; the app's suggestion list);
- `InteractiveWalk`: a person walking the tree's groups from best to worst in true return
  (the Interactive-DM; `groupwise.query.interactive`).
"""

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Literal, Protocol

import numpy as np

from groupwise.behaviour import group_candidates
from groupwise.behaviour.pool import BehaviourPool
from groupwise.config import TreeConfig
from groupwise.preferences.judgement import MAX_GROUP
from groupwise.query.groups import (
    GroupCandidate,
    return_variance,
    suggest_groups,
)
from groupwise.query.interactive import chain_pairs, clear_gaps, evenly_spaced
from groupwise.query.pairwise import select_pairs
from groupwise.types import FloatArray


@dataclass(frozen=True)
class Query:
    """One comparison to ask: two disjoint groups of pool indices (a pair: groups of one)."""

    left: tuple[int, ...]
    right: tuple[int, ...]

    def __post_init__(self) -> None:
        if not self.left or not self.right:
            raise ValueError("both groups of a query need at least one behaviour")
        if set(self.left) & set(self.right):
            raise ValueError("a behaviour cannot be in both groups of a query")


class QueryStrategy(Protocol):
    """Proposes up to `n_queries` comparisons of `pool`, in the order to ask them."""

    def propose(
        self, pool: BehaviourPool, n_queries: int, rng: np.random.Generator
    ) -> list[Query]: ...


def pool_candidates(
    pool: BehaviourPool,
    tree: TreeConfig | None = None,
    levels: Sequence[int] = (1, 2),
    min_size: int = 2,
    max_size: int = MAX_GROUP,
    padding: bool = False,
) -> list[GroupCandidate]:
    """The pool's group candidates (SPEC §4), as the interface offers them.

    The pool's DTW distances (computed once per pool) → behaviour tree → the nodes at
    `levels` with `min_size` … `max_size` leaves, in the tree's pre-order. Empty for a pool
    of fewer than 2 behaviours.
    """
    if len(pool) < 2:
        return []
    nodes = group_candidates(pool.tree(tree), levels, min_size, max_size, padding)
    return [GroupCandidate(node.id, node.leaves) for node in nodes]


@dataclass(frozen=True)
class PairwiseQueries:
    """For each query the most disputed of `candidates` random pairs (ensemble variance of
    the return difference, SPEC §5)."""

    candidates: int = 10

    def propose(self, pool: BehaviourPool, n_queries: int, rng: np.random.Generator) -> list[Query]:
        if n_queries <= 0 or len(pool) < 2:
            return []
        pairs = select_pairs(pool.predicted_returns, n_queries, self.candidates, rng)
        return [Query((a,), (b,)) for a, b in pairs.tolist()]


@dataclass(frozen=True)
class _TreeGroups:
    """What both group strategies share: the tree's candidate groups (SPEC §4) and how often
    one behaviour may be asked in a round's list."""

    tree: TreeConfig = field(default_factory=TreeConfig)
    levels: tuple[int, ...] = (1, 2)
    min_group: int = 2
    max_group: int = MAX_GROUP
    max_uses: int = 2
    padding: bool = False
    """Offer the tree's padding nodes too (groups of one among them; `group_candidates`)."""

    def candidates(self, pool: BehaviourPool) -> list[GroupCandidate]:
        return pool_candidates(
            pool, self.tree, self.levels, self.min_group, self.max_group, self.padding
        )


@dataclass(frozen=True)
class GroupSuggestions(_TreeGroups):
    """The best-scoring suggested group comparisons of the pool (SPEC §5).

    Suggestions are ranked by the group-variance score over the disjoint pairs of tree
    candidates; each candidate appears in at most `max_uses` suggestions of one list.
    With `refill` a list that is used up is followed by the next one over the pairs not yet
    asked (a pool of 2 × queries behaviours has far fewer candidate nodes than queries, so
    one list rarely covers the round). The intra term uses `pool.step_variance`; a pool
    without it falls back to Var_k[R_k(f)] / L (`query.groups.return_variance`).
    """

    refill: bool = True

    def propose(self, pool: BehaviourPool, n_queries: int, rng: np.random.Generator) -> list[Query]:
        del rng  # the list is a function of the pool
        if n_queries <= 0 or len(pool) < 2:
            return []
        candidates = self.candidates(pool)
        intra = pool.step_variance
        if intra is None:
            intra = return_variance(pool.predicted_returns, pool.fragments[0].length)
        suggestions = suggest_groups(
            pool.predicted_returns,
            intra,
            candidates,
            n_queries,
            self.max_uses,
            self.refill,
        )
        return [Query(s.left.members, s.right.members) for s in suggestions]


@dataclass(frozen=True)
class InteractiveWalk(_TreeGroups):
    """Groups compared down the ranking of their true returns (`query.interactive`).

    A simulated person who sees every behaviour's quality. `rank` orders the tree's groups
    by the "mean" or the "sum" of their members' true returns; `min_gap` > 0 (the
    "interactive-distinct" DM) pairs a group only with one at least that much lower;
    `clear` (a z, with `noise_sd` = L·σ) pairs it only with one clearly worse
    (`interactive.clear_gaps`) and repeats passes, each allowing one more use per behaviour,
    until `n_queries` comparisons are found or none is left; otherwise `passes` walks.
    `perceived_noise`, when set, gives that noise sd per pool from its true returns instead
    (a calibrated teacher's, `teachers.calibration.calibrated_noise_sd`). A pool in which no
    partner is clear (every behaviour scores alike, as a case-study target's early pools
    do) is walked as "interactive-mean" walks it, rather than asked nothing.
    """

    rank: Literal["mean", "sum"] = "mean"
    min_gap: float = 0.0
    passes: int = 1
    clear: float | None = None
    noise_sd: float = 0.0
    perceived_noise: Callable[[FloatArray], float] | None = None

    def propose(self, pool: BehaviourPool, n_queries: int, rng: np.random.Generator) -> list[Query]:
        del rng  # the walk is a function of the pool
        if n_queries <= 0 or len(pool) < 2:
            return []
        candidates = self.candidates(pool)
        true = pool.true_returns
        members = [c.members for c in candidates]
        values = [true[list(m)] for m in members]
        means = np.array([v.mean() for v in values])
        if self.clear is None:
            scores = means if self.rank == "mean" else np.array([v.sum() for v in values])
            pairs = chain_pairs(members, scores, self.max_uses, self.min_gap, self.passes)
        else:  # clear differences are differences of means: rank by the mean
            spreads = np.array([v.std() for v in values])
            noise_sd = self.noise_sd if self.perceived_noise is None else self.perceived_noise(true)
            gaps = clear_gaps(means, spreads, noise_sd, self.clear)
            pairs, found = [], -1
            for uses in range(self.max_uses, self.max_uses + len(pool)):
                pairs = chain_pairs(members, means, uses, gaps, passes=uses)
                if len(pairs) >= n_queries or len(pairs) == found:
                    break
                found = len(pairs)
            if not pairs:  # nothing clear: the paper's text's walk
                pairs = chain_pairs(members, means, self.max_uses)
        asked = [pairs[k] for k in evenly_spaced(len(pairs), n_queries)]
        return [Query(members[g], members[h]) for g, h in asked]
