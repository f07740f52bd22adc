"""Groupwise-DM (SPEC §7): asks the top group-variance suggestions, groups of at most 8.

The paper's no-exploration ablation: a DM who only ever takes the interface's suggested
comparisons (§5) and answers each with the group decision (`group_decision.py`).
"""

from dataclasses import dataclass, field

import numpy as np

from groupwise.behaviour import TreeConfig, build_tree, dtw_matrix, group_candidates, pool_features
from groupwise.oracles.group_decision import Teacher
from groupwise.pool import BehaviourPool
from groupwise.preferences.judgement import Judgement
from groupwise.query.groups import GroupCandidate, return_variance, suggest_groups


def pool_candidates(
    pool: BehaviourPool,
    tree: TreeConfig | None = None,
    levels: tuple[int, ...] = (1, 2),
    min_size: int = 2,
    max_size: int = 8,
) -> list[GroupCandidate]:
    """The pool's group candidates (SPEC §4), as the interface would offer them.

    z-scored [obs ; act] step features → exact DTW distances → behaviour tree → the nodes at
    `levels` with `min_size` … `max_size` leaves, in the tree's pre-order. Empty for a pool
    of fewer than 2 behaviours.
    """
    if len(pool) < 2:
        return []
    distances = dtw_matrix(pool_features(pool.fragments))
    nodes = group_candidates(build_tree(distances, tree), levels, min_size, max_size)
    return [GroupCandidate(node.id, node.leaves) for node in nodes]


@dataclass(frozen=True)
class GroupwiseDM:
    """Answers the best-scoring suggested group comparisons of each pool.

    Suggestions are ranked by the group-variance score over the disjoint pairs of tree
    candidates; each candidate appears in at most `max_uses` suggestions of one list.
    With `refill` a DM that used up the list asks for the next one over the pairs not yet
    asked (a pool of 2 × queries behaviours has far fewer candidate nodes than queries, so
    one list rarely covers the round). The intra term uses `pool.step_variance`; a pool
    without it falls back to Var_k[R_k(f)] / L (`query.groups.return_variance`).
    """

    teacher: Teacher = field(default_factory=Teacher)
    tree: TreeConfig = field(default_factory=TreeConfig)
    levels: tuple[int, ...] = (1, 2)
    min_group: int = 2
    max_group: int = 8
    max_uses: int = 2
    refill: bool = True

    def gather(self, pool: BehaviourPool, n_queries: int, rng: np.random.Generator) -> list[Judgement]:
        if n_queries <= 0 or len(pool) < 2:
            return []
        candidates = pool_candidates(pool, self.tree, self.levels, self.min_group, self.max_group)
        intra = pool.step_variance
        if intra is None:
            intra = return_variance(pool.predicted_returns, pool.fragments[0].length)
        suggestions = suggest_groups(
            pool.predicted_returns, intra, candidates, n_queries, self.max_uses, self.refill
        )
        judgements = (
            self.teacher.judge(pool, s.left.members, s.right.members, rng) for s in suggestions
        )
        return [j for j in judgements if j is not None]
