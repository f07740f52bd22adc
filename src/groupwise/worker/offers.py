"""A round's offer as the page shows it: the strategy's queries as the suggestion list (group
comparisons, each named by its tree nodes) and the pairwise queue (comparisons of two
single behaviours), and the exploration view's top-k pairwise edges (SPEC §5).

Nothing here chooses queries: that is the query strategy's (`groupwise.run.round.begin_round`).
"""

from collections.abc import Sequence

import numpy as np

from groupwise.behaviour import BehaviourTree
from groupwise.behaviour.pool import BehaviourPool
from groupwise.episodes.ids import behaviour_id
from groupwise.pool.publish import PreparedPool
from groupwise.query.pairwise import top_pairs
from groupwise.query.strategies import Query
from groupwise.storage.rounds import (
    BehaviourInput,
    GroupSuggestionInput,
    PairInput,
    PreparedRound,
)
from groupwise.types import FloatArray


def prepared_round(
    pool: BehaviourPool, published: PreparedPool, queries: Sequence[Query], edges: int
) -> PreparedRound:
    """What the database stores to open a round: the behaviours with their clips, the
    queries (`queries_as_rows`) and the top-`edges` pairwise edges."""
    returns = pool.predicted_returns
    suggestions, queue = queries_as_rows(queries, published.tree, returns)
    return PreparedRound(
        behaviours=tuple(
            BehaviourInput(i, published.clips[i], published.posters[i], f.true_return)
            for i, f in enumerate(pool.fragments)
        ),
        suggestions=suggestions,
        edges=pairwise_edges(returns, edges),
        queue=queue,
    )


def queries_as_rows(
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
