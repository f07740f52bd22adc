/**
 * Radial arc layout of the behaviour tree (SPEC §9, paper "Visualisation of the behaviour
 * space"): leaves form the innermost ring, each parent is an arc spanning its children in
 * the ring of its level, the root is not drawn, and the disc inside the leaf ring is left for
 * the edges. Every leaf gets the same angle, in the tree's child order (d3-hierarchy's
 * partition of the leaf counts).
 *
 * The chart's centre (issue 40): laid out around a cluster instead of the root, only that
 * cluster's descendants are drawn, its leaves share the whole ring and its children's level
 * is the outermost ring, so the 50 leaves of a cluster get the ring 1,000 shared before.
 *
 * Angles follow d3-shape's arc convention: radians clockwise from 12 o'clock, so a point is
 * (r sin a, -r cos a).
 */
import { partition } from "d3-hierarchy";
import { type Tree, type TreeJson, type TreeNode, subtreeHierarchy } from "./tree";

export interface LayoutOptions {
  /** Outer radius of the outermost ring. */
  radius: number;
  /** Radius of the disc inside the leaf ring, as a fraction of `radius`. */
  disc: number;
  /** Gap between rings (same units as radius). */
  ringGap: number;
  /** The leaf ring's width relative to a parent ring (leaves are the main targets). */
  leafWeight: number;
  /** Gap between neighbouring arcs (arc length, same units as radius). */
  arcGap: number;
  /** Gap between the leaf ring and the ends of the edges. */
  edgeGap: number;
  /** The node the chart is centred on (its descendants are drawn); default the root. */
  centre?: TreeNode | null;
}

export const DEFAULT_LAYOUT: LayoutOptions = {
  radius: 480,
  disc: 0.56,
  ringGap: 3,
  leafWeight: 1.35,
  arcGap: 1.6,
  edgeGap: 14,
};

export interface Arc {
  node: TreeNode;
  /** Ring index: the node's level (leaves 0, innermost). */
  ring: number;
  /** Angular span of the node's leaves, unpadded. */
  start: number;
  end: number;
  /** Drawn angles, padded by `arcGap` on both sides. */
  a0: number;
  a1: number;
  r0: number;
  r1: number;
}

export interface RadialLayout {
  /** The node the layout is centred on (not drawn): the root, or a cluster. */
  centre: TreeNode;
  /** Every drawn node (the centre's descendants), outer rings first, each ring by angle. */
  arcs: Arc[];
  byId: Map<string, Arc>;
  /** Ring index -> its arcs by angle. */
  rings: Arc[][];
  /** Rings drawn: the centre's level. */
  levels: number;
  radius: number;
  /** Inner radius of the leaf ring. */
  discRadius: number;
  /** Radius at which edges meet their leaves. */
  edgeRadius: number;
}

export function polar(angle: number, r: number): [number, number] {
  return [r * Math.sin(angle), -r * Math.cos(angle)];
}

/** Inner and outer radius of each ring (index = level). */
export function ringRadii(levels: number, o: LayoutOptions): Array<[number, number]> {
  const inner = o.radius * o.disc;
  const weights = Array.from({ length: levels }, (_, i) => (i === 0 ? o.leafWeight : 1));
  const total = weights.reduce((s, w) => s + w, 0);
  const band = o.radius - inner - o.ringGap * (levels - 1);
  const out: Array<[number, number]> = [];
  let r = inner;
  for (const w of weights) {
    const width = (band * w) / total;
    out.push([r, r + width]);
    r += width + o.ringGap;
  }
  return out;
}

export function radialLayout(tree: Tree, options: Partial<LayoutOptions> = {}): RadialLayout {
  const o = { ...DEFAULT_LAYOUT, ...options };
  const centre = o.centre && !o.centre.isLeaf ? o.centre : tree.root;
  const levels = Math.max(1, centre === tree.root ? tree.levels : centre.level);
  const radii = ringRadii(levels, o);
  const rings: Arc[][] = Array.from({ length: levels }, () => []);
  const byId = new Map<string, Arc>();
  // Angles: a partition of the full circle by leaf counts, in child order (every leaf the
  // same angle); radii: the ring of the node's level.
  const parts = partition<TreeJson>().size([2 * Math.PI, levels])(subtreeHierarchy(centre).count());
  for (const d of parts.descendants()) {
    const node = tree.nodes.get(d.data.id);
    if (!node || node === centre || node.level >= levels) continue;
    const ring = Math.max(0, node.level);
    const [r0, r1] = radii[ring]!;
    const span = d.x1 - d.x0;
    const pad = Math.min(o.arcGap / ((r0 + r1) / 2), span * 0.2) / 2;
    const arc: Arc = { node, ring, start: d.x0, end: d.x1, a0: d.x0 + pad, a1: d.x1 - pad, r0, r1 };
    rings[ring]!.push(arc);
    byId.set(node.id, arc);
  }
  for (const ring of rings) ring.sort((x, y) => x.start - y.start || x.end - y.end);
  const arcs = rings.slice().reverse().flat();
  const discRadius = radii[0]![0];
  return {
    centre,
    arcs,
    byId,
    rings,
    levels,
    radius: o.radius,
    discRadius,
    edgeRadius: Math.max(0, discRadius - o.edgeGap),
  };
}

/** Centre angle of a node's span. */
export function midAngle(arc: Pick<Arc, "start" | "end">): number {
  return (arc.start + arc.end) / 2;
}

/**
 * The arc an arrow key leads to in the chart's keyboard navigation: ←/→ the previous/next
 * arc of the same ring (wrapping), Home/End its first/last, ↑ the enclosing arc (outwards),
 * ↓ the first child (inwards); null where there is none; undefined for other keys.
 */
export function neighbourArc(layout: RadialLayout, arc: Arc, key: string): Arc | null | undefined {
  const ring = layout.rings[arc.ring] ?? [];
  const i = ring.indexOf(arc);
  switch (key) {
    case "ArrowRight":
      return ring[(i + 1) % ring.length] ?? null;
    case "ArrowLeft":
      return ring[(i - 1 + ring.length) % ring.length] ?? null;
    case "Home":
      return ring[0] ?? null;
    case "End":
      return ring[ring.length - 1] ?? null;
    case "ArrowUp": {
      const p = arc.node.parent;
      return (p && layout.byId.get(p.id)) || null;
    }
    case "ArrowDown": {
      const c = arc.node.children[0];
      return (c && layout.byId.get(c.id)) || null;
    }
    default:
      return undefined;
  }
}

/**
 * The arc drawn at the point (x, y) of the layout's coordinates (centred on the disc), or
 * null in the disc, beyond the outer ring, or between rings farther than `tolerance` from
 * one. Angles use the arcs' unpadded spans, so the thin gaps between neighbours belong to
 * an arc too. The chart asks when a click or context menu reaches the SVG rather than an
 * arc's path (issue 23).
 */
export function arcAt(layout: RadialLayout, x: number, y: number, tolerance = 2): Arc | null {
  const r = Math.hypot(x, y);
  let angle = Math.atan2(x, -y);
  if (angle < 0) angle += 2 * Math.PI;
  for (const ring of layout.rings) {
    const first = ring[0];
    if (!first || r < first.r0 - tolerance || r > first.r1 + tolerance) continue;
    for (const arc of ring) if (angle >= arc.start && angle < arc.end) return arc;
  }
  return null;
}
