"""The behaviour tree as JSON, the form the page reads and a pool's files keep (`to_json`,
read back by `from_json`):

    {
      "format": "groupwise.behaviour-tree/1",
      "levels": 4, "method": "complete", "bands": "linear",
      "thresholds": [t_1, ..., t_levels],       # floats, t_levels = root height
      "leaf_order": [i, ...],                   # behaviour indices, left to right
      "root": NODE
    }
    NODE = {
      "id": "m17", "kind": "merge" | "padding" | "leaf", "level": 2,
      "height": 1.25,                           # merge height; a padding node repeats its
                                                # child's, a leaf has 0
      "size": 3, "leaves": [4, 0, 9],           # behaviour indices under it, in order
      "children": [NODE, ...]                   # ordered; [] for a leaf
    }
    a leaf NODE also has "behaviour": i and "extra": {...}, the per-leaf slot (clip URL,
    poster URL, ...) filled by `to_json`'s `leaf_extra` argument ({} without it).
"""

from collections.abc import Callable, Mapping
from typing import Any

from groupwise.behaviour.tree import BehaviourTree, TreeNode

JSON_FORMAT = "groupwise.behaviour-tree/1"


LeafExtra = Callable[[int], Mapping[str, Any]] | Mapping[int, Mapping[str, Any]]
"""Per-leaf JSON fields: a function of the behaviour index, or a mapping from it."""


def to_json(tree: BehaviourTree, leaf_extra: LeafExtra | None = None) -> dict[str, Any]:
    """The JSON-serialisable form of a tree (format in the module docstring).

    leaf_extra fills each leaf's "extra" object (e.g. {"clip": url, "poster": url}); a
    mapping may leave behaviours out.
    """

    def extra(i: int) -> dict[str, Any]:
        if leaf_extra is None:
            return {}
        if isinstance(leaf_extra, Mapping):
            return dict(leaf_extra.get(i, {}))
        return dict(leaf_extra(i))

    def encode(node: TreeNode) -> dict[str, Any]:
        out: dict[str, Any] = {
            "id": node.id,
            "kind": node.kind,
            "level": node.level,
            "height": node.height,
            "size": node.size,
            "leaves": list(node.leaves),
            "children": [encode(c) for c in node.children],
        }
        if node.kind == "leaf":
            out["behaviour"] = node.behaviour
            out["extra"] = extra(node.behaviour)
        return out

    return {
        "format": JSON_FORMAT,
        "levels": tree.levels,
        "method": tree.method,
        "bands": tree.bands,
        "thresholds": list(tree.thresholds),
        "leaf_order": list(tree.leaf_order),
        "root": encode(tree.root),
    }


def from_json(data: Mapping[str, Any]) -> BehaviourTree:
    """Rebuild a tree from `to_json` output (leaf "extra" fields are not part of the tree)."""
    if data.get("format") != JSON_FORMAT:
        raise ValueError(f"not a {JSON_FORMAT} document: format {data.get('format')!r}")

    def decode(obj: Mapping[str, Any]) -> TreeNode:
        children = tuple(decode(c) for c in obj["children"])
        leaves = tuple(int(i) for i in obj["leaves"])
        if children and leaves != tuple(i for c in children for i in c.leaves):
            raise ValueError(f"node {obj['id']}: leaves disagree with its children")
        height = float(obj["height"])
        return TreeNode(str(obj["id"]), int(obj["level"]), obj["kind"], children, leaves, height)

    return BehaviourTree(
        root=decode(data["root"]),
        levels=int(data["levels"]),
        thresholds=tuple(float(t) for t in data["thresholds"]),
        method=str(data["method"]),
        bands=str(data["bands"]),
    )
