/**
 * The round's behaviour tree, indexed for the views.
 *
 * Accepts the tree of `GET …/rounds/{r}/tree` (docs/app.md): nested nodes with `id`,
 * `level` (leaves 0, the root `levels`) and ordered `children`; a leaf's `clip` and `poster`
 * either on the node or in its `extra` object (`behaviour.to_json`). Child order is kept: it
 * is the dendrogram's leaf order, so similar behaviours sit side by side.
 *
 * d3-hierarchy does the walking (depth, leaf order, the path through the lowest common
 * ancestor); `TreeNode` is the views' flat, id-keyed face of its nodes.
 */
import { type HierarchyNode, hierarchy } from "d3-hierarchy";

export interface TreeJson {
  id: string;
  level: number;
  children: TreeJson[];
  behaviour?: number | null;
  clip?: string | null;
  poster?: string | null;
  extra?: { clip?: string; poster?: string };
}

export interface TreeNode {
  id: string;
  level: number;
  parent: TreeNode | null;
  children: TreeNode[];
  /** Leaf ids under this node (itself for a leaf), left to right. */
  leaves: string[];
  /** Distance from the root (root 0). */
  depth: number;
  isLeaf: boolean;
  behaviour?: number;
  clip?: string;
  poster?: string;
}

export interface Tree {
  root: TreeNode;
  /** The root's level; leaves are level 0. */
  levels: number;
  nodes: Map<string, TreeNode>;
  /** Leaves left to right. */
  leaves: TreeNode[];
  /** Leaf id -> position in `leaves`. */
  leafIndex: Map<string, number>;
}

type Hierarchy = HierarchyNode<TreeJson>;
const hierarchyOf = new WeakMap<TreeNode, Hierarchy>();
const nodeOf = new WeakMap<Hierarchy, TreeNode>();

/** Indexes a tree; throws on a duplicate node id (ids must be unique per round). */
export function buildTree(json: TreeJson, levels?: number): Tree {
  const nodes = new Map<string, TreeNode>();
  const top = hierarchy(json, (j) => j.children);
  top.eachBefore((d) => {
    const j = d.data;
    if (nodes.has(j.id)) throw new Error(`duplicate node id ${j.id} in the tree`);
    const parent = d.parent ? nodeOf.get(d.parent)! : null;
    const node: TreeNode = {
      id: j.id,
      level: j.level,
      parent,
      children: [],
      leaves: d.leaves().map((leaf) => leaf.data.id),
      depth: d.depth,
      isLeaf: !d.children,
    };
    if (node.isLeaf) {
      if (j.behaviour !== undefined && j.behaviour !== null) node.behaviour = j.behaviour;
      const clip = j.clip ?? j.extra?.clip;
      const poster = j.poster ?? j.extra?.poster;
      if (clip) node.clip = clip;
      if (poster) node.poster = poster;
    }
    parent?.children.push(node);
    nodes.set(j.id, node);
    hierarchyOf.set(node, d);
    nodeOf.set(d, node);
  });
  const root = nodeOf.get(top)!;
  const leaves = top.leaves().map((d) => nodeOf.get(d)!);
  const leafIndex = new Map(leaves.map((leaf, i) => [leaf.id, i]));
  return { root, levels: levels ?? root.level, nodes, leaves, leafIndex };
}

/** The path of nodes from leaf `a` up to the lowest common ancestor and down to `b`. */
export function treePath(tree: Tree, a: string, b: string): TreeNode[] {
  const x = tree.nodes.get(a);
  const y = tree.nodes.get(b);
  if (!x || !y) throw new Error(`unknown node ${x ? b : a}`);
  return hierarchyOf.get(x)!.path(hierarchyOf.get(y)!).map((d) => nodeOf.get(d)!);
}

/** Ancestors of a node, nearest first, root last (the node itself excluded). */
export function ancestors(node: TreeNode): TreeNode[] {
  return hierarchyOf.get(node)!.ancestors().slice(1).map((d) => nodeOf.get(d)!);
}

/** A fresh d3 hierarchy of the subtree under `node` (depth 0 at `node`), for d3-hierarchy's
 * layouts (the chart's partition, `layout.ts`); its nodes' `data` are the tree's JSON. */
export function subtreeHierarchy(node: TreeNode): HierarchyNode<TreeJson> {
  return hierarchyOf.get(node)!.copy();
}
