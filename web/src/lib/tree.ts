/**
 * The round's behaviour tree, indexed for the views.
 *
 * Accepts the tree of `GET …/rounds/{r}/tree` (docs/app.md): nested nodes with `id`,
 * `level` (leaves 0, the root `levels`) and ordered `children`; a leaf's `clip` and `poster`
 * either on the node or in its `extra` object (`behaviour.to_json`). Child order is kept: it
 * is the dendrogram's leaf order, so similar behaviours sit side by side.
 */

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

/** Indexes a tree; throws on a duplicate node id (ids must be unique per round). */
export function buildTree(json: TreeJson, levels?: number): Tree {
  const nodes = new Map<string, TreeNode>();
  const leaves: TreeNode[] = [];

  function visit(j: TreeJson, parent: TreeNode | null, depth: number): TreeNode {
    if (nodes.has(j.id)) throw new Error(`duplicate node id ${j.id} in the tree`);
    const isLeaf = j.children.length === 0;
    const node: TreeNode = {
      id: j.id,
      level: j.level,
      parent,
      children: [],
      leaves: [],
      depth,
      isLeaf,
    };
    nodes.set(j.id, node);
    if (isLeaf) {
      node.leaves = [j.id];
      if (j.behaviour !== undefined && j.behaviour !== null) node.behaviour = j.behaviour;
      const clip = j.clip ?? j.extra?.clip;
      const poster = j.poster ?? j.extra?.poster;
      if (clip) node.clip = clip;
      if (poster) node.poster = poster;
      leaves.push(node);
    } else {
      for (const child of j.children) {
        const c = visit(child, node, depth + 1);
        node.children.push(c);
        for (const leaf of c.leaves) node.leaves.push(leaf);
      }
    }
    return node;
  }

  const root = visit(json, null, 0);
  const leafIndex = new Map(leaves.map((leaf, i) => [leaf.id, i]));
  return { root, levels: levels ?? root.level, nodes, leaves, leafIndex };
}

/** The path of nodes from leaf `a` up to the lowest common ancestor and down to `b`. */
export function treePath(tree: Tree, a: string, b: string): TreeNode[] {
  let x = tree.nodes.get(a);
  let y = tree.nodes.get(b);
  if (!x || !y) throw new Error(`unknown node ${x ? b : a}`);
  const up: TreeNode[] = [];
  const down: TreeNode[] = [];
  while (x.depth > y.depth) {
    up.push(x);
    x = x.parent!;
  }
  while (y.depth > x.depth) {
    down.push(y);
    y = y.parent!;
  }
  while (x !== y) {
    up.push(x);
    down.push(y);
    x = x.parent!;
    y = y.parent!;
  }
  up.push(x); // the lowest common ancestor, once
  return up.concat(down.reverse());
}

/** Ancestors of a node, nearest first, root last (the node itself excluded). */
export function ancestors(node: TreeNode): TreeNode[] {
  const out: TreeNode[] = [];
  for (let p = node.parent; p; p = p.parent) out.push(p);
  return out;
}
