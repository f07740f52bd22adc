"""The n-ary behaviour tree of the exploration view and of group candidates (SPEC §4).

Construction, from condensed DTW distances of N behaviours:

1. SciPy agglomerative clustering (`linkage.py`) gives a binary dendrogram with merge
   heights; D is the root's height.
2. Level bands. `levels` thresholds t_1 <= ... <= t_levels = D:
   - "counts" (default): levels by target cluster counts, not by height. With
     k = N^(1/levels), level l should hold about N / k^l clusters (for N = 100 and 4 levels:
     32, 10, 3, then the root), so t_l is the height of the first merge that would leave
     fewer: after the j lowest merges N − j clusters remain. Every level then holds real
     groups whatever the distribution of the distances; DTW distances of z-scored windows
     are concentrated (the lowest merge is already a large fraction of D), and fixed
     fractions of D left levels 1–2 without a single group on HalfCheetah;
   - "linear": t_k = D k / levels (SPEC §4, the paper's cut);
   - "geometric": t_k = D 2^(k - levels), i.e. D/8, D/4, D/2, D for 4 levels: the lower
     levels get the narrower bands, so close behaviours are split into finer groups.
   A merge of height h gets the first level k whose threshold exceeds h (t_k > h); a merge
   that no threshold exceeds (the root, and any merge as high as the root) gets the top
   level. So a merge exactly at t_k goes to level k + 1. Leaves are level 0.
   Size caps (`behaviour.balance`; on by default, `TreeConfig.balance` and `top_balance`):
   top down, a node with more leaves than its level's cap is split by its own sub-tree, so
   no top-level cluster holds more than top_balance times the mean size the cut aims for,
   none below the root more than half the pool, and every level-1 node is a group of at
   most MAX_GROUP (issues 22, 40).
3. n-ary tree. A merge with the same level as its parent is dissolved: its children take
   its place in the parent's child list, at the same position. Heights are monotone for
   every offered linkage, so a child's level never exceeds its parent's.
4. Padding. Where an edge skips levels (a level-3 node with a leaf child), single-child
   padding nodes are inserted at every level in between, so every leaf is at depth
   `levels` below the root and every node at level l is at depth levels - l. We chose
   uniform depth over variable-depth trees because the radial view then draws each level
   as one ring.
5. Order. Children keep the dendrogram's left-to-right order, so in-order leaves equal
   `scipy.cluster.hierarchy.leaves_list` and siblings that came from one dissolved merge
   stay adjacent.

Node ids (unique; the prototype's padding ids collided):
- "root" for the root (the last merge, or for N = 1 the padding above the only leaf);
- "b{i}" for the leaf of behaviour i;
- "m{c}" for the merge that SciPy numbers cluster c (N <= c < 2N - 1);
- "{id}@{l}" for the padding node at level l above the real node `id`; each real node has
  at most one padding node per level, so these never collide.

The JSON form the page reads: `behaviour.tree_json`.
"""

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Literal

import numpy as np

from groupwise.behaviour.balance import balance_levels
from groupwise.behaviour.bands import BANDS, assign_levels
from groupwise.behaviour.linkage import (
    as_condensed,
    linkage_matrix,
    pool_size,
)
from groupwise.config import TreeConfig
from groupwise.episodes.ids import behaviour_id
from groupwise.preferences.judgement import MAX_GROUP
from groupwise.types import FloatArray

NodeKind = Literal["leaf", "merge", "padding"]


@dataclass(frozen=True)
class TreeNode:
    """One node of the n-ary tree."""

    id: str
    level: int
    kind: NodeKind
    children: tuple["TreeNode", ...]  # left to right; () for a leaf
    leaves: tuple[int, ...]  # behaviour indices under this node, left to right
    height: float  # merge height; padding repeats its child's; 0 for a leaf

    @property
    def size(self) -> int:
        return len(self.leaves)

    @property
    def behaviour(self) -> int:
        """The behaviour index of a leaf."""
        if self.kind != "leaf":
            raise ValueError(f"node {self.id} is a {self.kind}, not a leaf")
        return self.leaves[0]


@dataclass(frozen=True)
class BehaviourTree:
    """The n-ary tree of one pool, every leaf at depth `levels`."""

    root: TreeNode
    levels: int
    thresholds: tuple[float, ...]  # (levels,) t_1..t_levels, t_levels = root height
    method: str
    bands: str

    @property
    def leaf_order(self) -> tuple[int, ...]:
        """Behaviour indices left to right (equal to SciPy's `leaves_list`)."""
        return self.root.leaves

    def nodes(self) -> Iterator[TreeNode]:
        """Every node, pre-order (parent first, children left to right)."""
        stack = [self.root]
        while stack:
            node = stack.pop()
            yield node
            stack.extend(reversed(node.children))

    @cached_property
    def _by_id(self) -> dict[str, TreeNode]:
        return {n.id: n for n in self.nodes()}

    @cached_property
    def _parents(self) -> dict[str, TreeNode]:
        return {c.id: n for n in self.nodes() for c in n.children}

    def node(self, node_id: str) -> TreeNode:
        """The node with this id; raises KeyError."""
        return self._by_id[node_id]

    def parent(self, node_id: str) -> TreeNode | None:
        """The parent of a node, None for the root; raises KeyError for an unknown id."""
        if node_id not in self._by_id:
            raise KeyError(node_id)
        return self._parents.get(node_id)

    def at_level(self, level: int) -> list[TreeNode]:
        """The nodes at one level, left to right (padding included)."""
        return [n for n in self.nodes() if n.level == level]


def _leaf(i: int) -> TreeNode:
    return TreeNode(id=behaviour_id(i), level=0, kind="leaf", children=(), leaves=(i,), height=0.0)


def _pad(node: TreeNode, parent_level: int) -> TreeNode:
    """Wrap a node in padding nodes for every level strictly between it and its parent."""
    base = node.id
    for level in range(node.level + 1, parent_level):
        node = TreeNode(
            id=f"{base}@{level}",
            level=level,
            kind="padding",
            children=(node,),
            leaves=node.leaves,
            height=node.height,
        )
    return node


def _merge(node_id: str, level: int, children: list[TreeNode], height: float) -> TreeNode:
    leaves = tuple(i for c in children for i in c.leaves)
    return TreeNode(node_id, level, "merge", tuple(children), leaves, height)


def build_tree(distances: FloatArray, config: TreeConfig | None = None) -> BehaviourTree:
    """The n-ary behaviour tree (module docstring) of condensed (N (N - 1) / 2,) or square
    (N, N) distances; N >= 1. Root height 0 (all behaviours identical) is valid: every merge
    then belongs to the root.
    """
    cfg = config or TreeConfig()
    d = as_condensed(distances)
    n = pool_size(d.shape[0])
    if n == 1:
        thresholds = BANDS[cfg.bands](np.zeros(0), cfg.levels)
        leaf = _pad(_leaf(0), cfg.levels)
        root = TreeNode("root", cfg.levels, "padding", (leaf,), leaf.leaves, 0.0)
        return BehaviourTree(root, cfg.levels, thresholds, cfg.method, cfg.bands)

    z = linkage_matrix(d, cfg.method)
    heights = z[:, 2]
    thresholds = BANDS[cfg.bands](heights, cfg.levels)
    merge_levels = assign_levels(heights, thresholds)
    merge_levels[-1] = cfg.levels

    n_clusters = 2 * n - 1
    level = np.zeros(n_clusters, dtype=np.int64)
    level[n:] = merge_levels
    parent = np.full(n_clusters, -1, dtype=np.int64)
    for r in range(n - 2, -1, -1):
        for child in (int(z[r, 0]), int(z[r, 1])):
            parent[child] = n + r
            # heights are monotone for every offered linkage; clamping top-down keeps the
            # levels consistent even if rounding ever made a child higher than its parent
            level[child] = min(level[child], level[n + r]) if child >= n else 0
    if cfg.balance is not None:
        balance_levels(z, level, parent, d, cfg.balance, cfg.top_balance)
    # a merge at its parent's level is dissolved into the parent
    dissolved = np.zeros(n_clusters, dtype=bool)
    dissolved[n:-1] = level[n:-1] == level[parent[n:-1]]

    # bottom up (SciPy numbers children before parents); iterative, so a chain of 1000
    # merges does not hit Python's recursion limit
    spliced: dict[int, list[TreeNode]] = {}  # dissolved merge -> its n-ary children
    built: dict[int, TreeNode] = {}  # kept merge -> its node
    for r in range(n - 1):
        c = n + r
        lvl = int(level[c])
        children: list[TreeNode] = []
        for child in (int(z[r, 0]), int(z[r, 1])):
            if child < n:
                children.append(_pad(_leaf(child), lvl))
            elif dissolved[child]:
                children.extend(spliced.pop(child))
            else:
                children.append(_pad(built.pop(child), lvl))
        if dissolved[c]:
            spliced[c] = children
        else:
            node_id = "root" if c == n_clusters - 1 else f"m{c}"
            built[c] = _merge(node_id, lvl, children, float(heights[r]))
    root = built.pop(n_clusters - 1)
    return BehaviourTree(root, cfg.levels, thresholds, cfg.method, cfg.bands)


def group_candidates(
    tree: BehaviourTree,
    levels: Sequence[int] = (1, 2),
    min_size: int = 2,
    max_size: int = MAX_GROUP,
    padding: bool = False,
) -> list[TreeNode]:
    """Nodes that can be offered as one group (SPEC §4): at one of `levels`, with
    min_size..max_size leaves, in pre-order (left to right, parents before children).

    Padding nodes are left out: each has exactly the leaves of the real node below it, so
    it would repeat that node's group. With `padding` (the reference code's Interactive-DM)
    they are offered too, once per group of behaviours: a padding node over a leaf is a
    group of one.
    """
    wanted = set(levels)
    seen: set[tuple[int, ...]] = set()
    out = []
    for node in tree.nodes():
        if node.level not in wanted or not min_size <= node.size <= max_size:
            continue
        if node.kind == "padding" and (not padding or node.leaves in seen):
            continue
        seen.add(node.leaves)
        out.append(node)
    return out


def medoids(node: TreeNode, distances: FloatArray, k: int = 3) -> tuple[int, ...]:
    """Up to k representative behaviours of a node: its leaves with the smallest summed
    distance to the node's other leaves, best first (ties keep the leaf order).

    distances: condensed (N (N - 1) / 2,) or square (N, N) over the whole pool.
    """
    if k < 1:
        raise ValueError(f"k must be >= 1, got {k}")
    idx = np.asarray(node.leaves, dtype=np.int64)
    if idx.size == 1:
        return (int(idx[0]),)
    d = np.asarray(distances, dtype=np.float64)
    if d.ndim == 2:
        sub = d[np.ix_(idx, idx)]
    else:
        n = pool_size(d.shape[0])
        i, j = np.minimum.outer(idx, idx), np.maximum.outer(idx, idx)
        pos = n * i - i * (i + 1) // 2 + j - i - 1
        sub = np.where(i == j, 0.0, d[np.where(i == j, 0, pos)])
    order = np.argsort(sub.sum(axis=1), kind="stable")[:k]
    return tuple(int(idx[o]) for o in order)
