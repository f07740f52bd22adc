"""Size caps of the behaviour tree's levels (`behaviour.tree`, step 2; issues 22 and 40):
which merges a level's oversize nodes are split by.

A cut fixes how many clusters a level has, not how balanced they are: pools of a trained
policy are concentrated, and in a Hopper session round 1's top level held 3, 94 and 3
behaviours (issue 22). So, top down, a node at level l (1 <= l < levels) with more than
cap_l leaves is split by its own sub-tree: its merge moves up to its parent's level (and is
dissolved into it), so its two dendrogram children take its place at level l, each split
again while too big. With k = N^(1/levels), k^l is the mean cluster size the counts cut aims
for at level l, and

- level 1: MAX_GROUP (a level-1 node is a group a person picks: none is left unselectable
  for want of a split);
- levels 2 … levels - 2: max(MAX_GROUP, ceil(balance · k^l)), `TreeConfig.balance`;
- the top level (the root's children): max(MAX_GROUP, ceil(top_balance · N / k)),
  `TreeConfig.top_balance`, so no top-level cluster holds more than top_balance times the
  mean size of the k clusters the cut aims for (issue 40: with `balance` alone, 2, a
  Hopper pool's top level held [5, 49, 33, 13] of 100 and [348, 138, 14, 147, 30, 76, 247]
  of 1,000);
- no node below the root more than floor(N / 2).

Unless its behaviours are indistinguishable: at levels >= 2 a node whose mean pairwise
distance is at most half the pool's mean pairwise distance (`INDISTINCT_SPREAD`) is left
whole (its behaviours are closer to each other than most behaviours of the pool are to
their nearest neighbour, so a split could only be arbitrary). Level 1 is always split down
to its cap: it holds the groups a person picks.

Splitting only ever follows the dendrogram, so the leaf order and the tree's JSON are as
without caps; what changes is which merges are dissolved.
"""

import math

import numpy as np
from scipy.spatial.distance import squareform

from groupwise.preferences.judgement import MAX_GROUP
from groupwise.types import FloatArray, IntArray


def level_caps(
    n: int, levels: int, balance: float, top_balance: float | None = None
) -> tuple[int, ...]:
    """(levels - 1,) the most leaves a node at level 1 … levels - 1 may hold before it is
    split (module docstring): MAX_GROUP at level 1, max(MAX_GROUP, ceil(balance · k^l))
    above, at the top level (levels >= 3) at most max(MAX_GROUP, ceil(top_balance · N / k))
    too; never more than floor(N / 2)."""
    k = n ** (1.0 / levels)
    caps = [MAX_GROUP] + [max(MAX_GROUP, _ceil(balance * k**lv)) for lv in range(2, levels)]
    if top_balance is not None and levels >= 3:
        caps[-1] = min(caps[-1], max(MAX_GROUP, _ceil(top_balance * n / k)))
    return tuple(min(cap, n // 2) for cap in caps)


def _ceil(x: float) -> int:
    """ceil, forgiving rounding: 100^(2/4) is 10.000000000000002 in floating point."""
    return math.ceil(x - 1e-9)


INDISTINCT_SPREAD = 0.5
"""A node whose mean pairwise distance is at most this share of the pool's is left whole
above level 1 (module docstring). On the Hopper pools of issue 22 the tightest cluster of
more than a quarter of the pool had 0.59 of the pool's mean distance; a behaviour's
nearest neighbour was typically 0.59–0.71 of the median distance away
(docs/results/tree-balance)."""


def indistinguishable_spread(distances: FloatArray) -> float:
    """The largest mean pairwise distance of an indistinguishable node: INDISTINCT_SPREAD
    times the mean of the pool's condensed `distances` (module docstring)."""
    return INDISTINCT_SPREAD * float(np.mean(distances))


def balance_levels(
    z: FloatArray,
    level: IntArray,
    parent: IntArray,
    distances: FloatArray,
    balance: float,
    top_balance: float | None = None,
) -> None:
    """Apply the size caps (module docstring, `level_caps`) to the merge levels of a
    dendrogram, in place.

    z: SciPy linkage (N - 1, 4); level, parent: (2N - 1,) each cluster's level (leaves 0,
    the root `levels`, monotone) and parent (-1 for the root); distances: condensed.
    Only raises levels, each to its parent's, so they stay monotone.
    """
    n = z.shape[0] + 1
    top = int(level[-1])
    if n < 4 or top < 2:
        return
    caps = level_caps(n, top, balance, top_balance)
    square = squareform(distances)
    floor = indistinguishable_spread(distances)
    size = np.ones(2 * n - 1, dtype=np.int64)
    size[n:] = z[:, 3].astype(np.int64)
    children = z[:, :2].astype(np.int64)

    def leaves(c: int) -> list[int]:
        out, stack = [], [c]
        while stack:
            x = stack.pop()
            if x < n:
                out.append(x)
            else:
                stack.extend(children[x - n])
        return out

    def spread(c: int) -> float:
        idx = np.asarray(leaves(c))
        return float(square[np.ix_(idx, idx)].sum() / (len(idx) * (len(idx) - 1)))

    for upper in range(top, 1, -1):  # nodes at level upper - 1 under nodes at level upper
        at = upper - 1
        cap = caps[at - 1]
        below = level[:-1] <= at
        frontier = np.flatnonzero(below & (level[parent[:-1]] >= upper)).tolist()
        while frontier:
            c = frontier.pop()
            if c < n or size[c] <= cap or (at >= 2 and spread(c) <= floor):
                continue
            level[c] = upper  # dissolved into its parent: its children take its place
            frontier.extend(int(x) for x in children[c - n])
