/**
 * The exploration chart's centre (issue 40): the cluster the radial chart is laid out around
 * (`layout.ts`: its leaves then share the whole ring), the breadcrumb back out, which clicks
 * centre the chart instead of filling a group, and how many gestures a person needs to pick
 * one behaviour. Pure.
 */
import { type LayoutOptions, type RadialLayout, radialLayout } from "./layout";
import { MAX_GROUP } from "./selection";
import { type Tree, type TreeNode, ancestors } from "./tree";

/** A node the chart can centre on: a cluster of two behaviours or more. */
export function canCentre(node: TreeNode): boolean {
  return !node.isLeaf && node.leaves.length > 1;
}

/** The node the centre `id` names; the root for null, an unknown id or a node that is no
 * cluster (a leaf, a padding node over one behaviour). */
export function centreNode(tree: Tree, id: string | null): TreeNode {
  const node = id === null ? undefined : tree.nodes.get(id);
  return node && canCentre(node) ? node : tree.root;
}

/** The breadcrumb of a centre: the root first, the centre last (the root alone unfocused).
 * Padding nodes, which hold the same behaviours as their child, are left out. */
export function crumbs(tree: Tree, id: string | null): TreeNode[] {
  const centre = centreNode(tree, id);
  const path = [centre, ...ancestors(centre)].reverse();
  return path.filter((n, i) => i === 0 || i === path.length - 1 || n.children.length > 1);
}

/** The centre one step out: the nearest enclosing cluster that holds more than the centre
 * does (null: the root, the whole round). */
export function outward(tree: Tree, id: string | null): string | null {
  const centre = centreNode(tree, id);
  const up = ancestors(centre).find((n) => n.leaves.length > centre.leaves.length);
  return !up || up === tree.root ? null : up.id;
}

export interface ClusterClick {
  leaves: readonly string[];
  isLeaf: boolean;
  /** The modifier (Shift/Ctrl/⌘): add to the group. */
  add: boolean;
}

/** A click that centres the chart on the clicked arc instead of filling a group: a plain
 * click (either group) on a cluster too big to be a group (more than MAX_GROUP). */
export function centresOn(click: ClusterClick): boolean {
  return !click.isLeaf && !click.add && click.leaves.length > MAX_GROUP;
}

export interface PickGeometry {
  /** CSS pixels per layout unit (the chart's side over the SVG viewBox). */
  scale: number;
  /** The layout's options (radius etc.), as the chart draws it. */
  layout?: Partial<LayoutOptions>;
  /** The narrowest arc a person can pick, in CSS pixels along its middle. */
  minPx?: number;
  /** The chart's largest zoom (d3-zoom's scale extent). */
  maxZoom?: number;
}

/** An arc's width in CSS pixels along the middle of its ring. */
export function arcPx(arc: { a0: number; a1: number; r0: number; r1: number }, scale: number): number {
  return (arc.a1 - arc.a0) * ((arc.r0 + arc.r1) / 2) * scale;
}

/**
 * The gestures a person needs to pick behaviour `leaf` into a group, starting from the
 * whole round: each click centres the chart on the innermost enclosing cluster whose arc
 * is wide enough to click and too big to be a group; once no such click brings the leaf
 * wide enough, one wheel or pinch zoom magnifies it (up to `maxZoom`); then one click picks
 * it. Infinity when even that leaves it too narrow. `layouts` keeps the layout centred on
 * each cluster between calls over the same tree and geometry (a count for every leaf of
 * 1,000 lays out each centre once, not each leaf's).
 */
export function gesturesToPick(
  tree: Tree,
  leaf: string,
  geometry: PickGeometry,
  layouts: Map<TreeNode, RadialLayout> = new Map(),
): number {
  const minPx = geometry.minPx ?? 6;
  const maxZoom = geometry.maxZoom ?? 16;
  const target = tree.nodes.get(leaf);
  if (!target?.isLeaf) throw new Error(`unknown behaviour ${leaf}`);
  let centre = tree.root;
  let gestures = 0;
  for (;;) {
    let layout = layouts.get(centre);
    if (!layout) {
      layout = radialLayout(tree, { ...geometry.layout, centre });
      layouts.set(centre, layout);
    }
    const width = arcPx(layout.byId.get(leaf)!, geometry.scale);
    if (width >= minPx) return gestures + 1;
    const next = ancestors(target).find((n) => {
      const arc = layout.byId.get(n.id);
      return arc && n.leaves.length > MAX_GROUP && arcPx(arc, geometry.scale) >= minPx;
    });
    if (!next) return width * maxZoom >= minPx ? gestures + 2 : Number.POSITIVE_INFINITY;
    centre = next;
    gestures += 1;
  }
}
