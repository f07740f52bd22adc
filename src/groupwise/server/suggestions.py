"""What a round offers besides its pool, from the ensemble's predictions (SPEC §5).

Pure functions of the N × K predicted returns (and the per-behaviour step variance), so the
worker's `jobs.prepare` stays a composition: group suggestions over the tree's candidates,
the top-k pairwise edges of the exploration view, and the pairwise baseline's queue.
"""

from collections.abc import Sequence

import numpy as np

from groupwise.behaviour import BehaviourTree, TreeNode
from groupwise.config import LoopConfig
from groupwise.pool import behaviour_id
from groupwise.query.groups import GroupCandidate, suggest_groups
from groupwise.query.pairwise import select_pairs, top_pairs
from groupwise.query.strategies import Query
from groupwise.storage.rounds import GroupSuggestionInput, PairInput
from groupwise.types import FloatArray

MAX_GROUP_SUGGESTIONS = 1000
"""Group suggestions stored per round (the list is refilled once used up, SPEC §5)."""
CANDIDATE_PAIRS = LoopConfig().candidate_pairs
"""Random candidate pairs scored per pairwise query (SPEC §5)."""


def group_suggestions(
    returns: FloatArray, intra: FloatArray, nodes: tuple[TreeNode, ...]
) -> tuple[GroupSuggestionInput, ...]:
    """The suggestion list over the tree's group candidates (each node in at most 2
    suggestions per list; the list refilled over the pairs left when used up)."""
    candidates = [GroupCandidate(node.id, tuple(node.leaves)) for node in nodes]
    suggestions = suggest_groups(
        returns, intra, candidates, MAX_GROUP_SUGGESTIONS, max_uses=2, refill=True
    )
    return tuple(
        GroupSuggestionInput(
            left=tuple(behaviour_id(i) for i in g.left.members),
            right=tuple(behaviour_id(i) for i in g.right.members),
            left_node=g.left.id,
            right_node=g.right.id,
            score=float(g.score),
        )
        for g in suggestions
    )


def pairwise_edges(returns: FloatArray, k: int) -> tuple[PairInput, ...]:
    """The top-k pairs by Var_k[R_k(a) − R_k(b)], scores divided by the best: in (0, 1]."""
    if k <= 0 or len(returns) < 2:
        return ()
    pairs, scores = top_pairs(returns, k)
    top = float(scores[0]) if len(scores) else 0.0
    scaled = scores / top if top > 0 else np.ones_like(scores)
    return tuple(
        PairInput(behaviour_id(a), behaviour_id(b), float(max(s, 1e-6)))
        for (a, b), s in zip(pairs.tolist(), scaled.tolist(), strict=True)
    )


def pairwise_queue(
    returns: FloatArray, length: int, rng: np.random.Generator
) -> tuple[PairInput, ...]:
    """Up to `length` distinct pairs for the pairwise baseline, in the order asked: for each
    query the most disputed of `CANDIDATE_PAIRS` random pairs (SPEC §5)."""
    n = len(returns)
    if n < 2:
        return ()
    wanted = min(length, n * (n - 1) // 2)
    chosen = select_pairs(returns, wanted * 2, CANDIDATE_PAIRS, rng)
    seen: set[frozenset[int]] = set()
    queue = []
    for a, b in chosen.tolist():
        key = frozenset((a, b))
        if key in seen:
            continue
        seen.add(key)
        score = float(np.var(returns[a] - returns[b]))
        queue.append(PairInput(behaviour_id(a), behaviour_id(b), score))
        if len(queue) >= wanted:
            break
    return tuple(queue)


def suggestions_of(
    queries: Sequence[Query], tree: BehaviourTree, returns: FloatArray
) -> tuple[tuple[GroupSuggestionInput, ...], tuple[PairInput, ...]]:
    """A query strategy's proposals as a round's suggestion list and pairwise queue, in their
    order: each group is named by the tree node with exactly its behaviours (a leaf for a
    group of one); a query whose group is no tree node is left out of the suggestions (a
    person can still compose it in the chart). Scores are the ensemble's disagreement about
    the groups' mean returns, Var_k[mean R_k(A) − mean R_k(B)]."""
    nodes = {frozenset(node.leaves): node.id for node in tree.nodes() if node.kind != "padding"}
    groups, pairs = [], []
    for q in queries:
        difference = returns[list(q.left)].mean(axis=0) - returns[list(q.right)].mean(axis=0)
        score = float(np.var(difference)) if returns.shape[1] else 0.0
        if len(q.left) == 1 and len(q.right) == 1:
            pairs.append(PairInput(behaviour_id(q.left[0]), behaviour_id(q.right[0]), score))
        left, right = nodes.get(frozenset(q.left)), nodes.get(frozenset(q.right))
        if left is None or right is None:
            continue
        groups.append(
            GroupSuggestionInput(
                left=tuple(behaviour_id(i) for i in q.left),
                right=tuple(behaviour_id(i) for i in q.right),
                left_node=left,
                right_node=right,
                score=score,
            )
        )
    return tuple(groups), tuple(pairs)
