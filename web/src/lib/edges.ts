/**
 * Hierarchical edge bundling (Holten 2006; SPEC §9): an edge between two leaves follows the
 * tree from one leaf up to their lowest common ancestor and down to the other, each node a
 * control point of a B-spline straightened by `beta` (d3.curveBundle; 0 straight, 1 fully
 * bundled; default 0.85).
 *
 * Control points: a leaf sits on the edge radius at its centre angle; an inner node at level
 * l sits at its centre angle on radius edgeRadius · (levels − l) / levels, so the root is
 * the centre of the disc.
 */
import { curveBundle, line } from "d3-shape";
import type { RadialLayout } from "./layout";
import { midAngle, polar } from "./layout";
import type { Tree, TreeNode } from "./tree";
import { treePath } from "./tree";

export const DEFAULT_BETA = 0.85;

export type Point = [number, number];

/** Where a node sits as a control point of the edges routed through it. */
export function controlPoint(tree: Tree, layout: RadialLayout, node: TreeNode): Point {
  if (node === tree.root) return [0, 0];
  const arc = layout.byId.get(node.id);
  if (!arc) return [0, 0];
  const level = Math.min(Math.max(node.level, 0), layout.levels);
  const r = (layout.edgeRadius * (layout.levels - level)) / layout.levels;
  return polar(midAngle(arc), r);
}

/** Control points of the edge a–b: a, its ancestors up to the LCA, down to b. */
export function edgePoints(tree: Tree, layout: RadialLayout, a: string, b: string): Point[] {
  return treePath(tree, a, b).map((node) => controlPoint(tree, layout, node));
}

/** The SVG path data of a bundled edge (tests, SVG drawing). */
export function edgePath(points: Point[], beta = DEFAULT_BETA): string {
  return line().curve(curveBundle.beta(beta))(points) ?? "";
}

/** Records a d3 curve as a polyline, each cubic segment flattened into `steps` chords. */
class Flattener {
  readonly points: Point[] = [];
  constructor(private readonly steps: number) {}
  private last(): Point {
    return this.points[this.points.length - 1] ?? [0, 0];
  }
  moveTo(x: number, y: number): void {
    this.points.push([x, y]);
  }
  lineTo(x: number, y: number): void {
    this.points.push([x, y]);
  }
  bezierCurveTo(x1: number, y1: number, x2: number, y2: number, x: number, y: number): void {
    const [x0, y0] = this.last();
    for (let i = 1; i <= this.steps; i++) {
      const t = i / this.steps;
      const u = 1 - t;
      const a = u * u * u;
      const b = 3 * u * u * t;
      const c = 3 * u * t * t;
      const d = t * t * t;
      this.points.push([a * x0 + b * x1 + c * x2 + d * x, a * y0 + b * y1 + c * y2 + d * y]);
    }
  }
  closePath(): void {}
}

/** The bundled curve through `points` as a polyline (for drawing in colour bins). */
export function flattenEdge(points: Point[], beta = DEFAULT_BETA, steps = 4): Point[] {
  const f = new Flattener(steps);
  line().curve(curveBundle.beta(beta)).context(f as unknown as CanvasRenderingContext2D)(points);
  return f.points;
}

/**
 * The colour bin of each segment of a polyline: segment i (points i → i+1) falls in bin
 * floor(k · f), f the fraction of the line's length at the segment's middle. One pass, so
 * hundreds of edges bin in well under a millisecond.
 */
export function segmentBins(points: readonly Point[], k: number): Uint8Array {
  const n = Math.max(0, points.length - 1);
  const lengths = new Float64Array(n);
  let total = 0;
  for (let i = 0; i < n; i++) {
    const [x0, y0] = points[i]!;
    const [x1, y1] = points[i + 1]!;
    lengths[i] = Math.hypot(x1 - x0, y1 - y0);
    total += lengths[i]!;
  }
  const bins = new Uint8Array(n);
  let run = 0;
  for (let i = 0; i < n; i++) {
    const mid = total > 0 ? (run + lengths[i]! / 2) / total : (i + 0.5) / n;
    bins[i] = Math.min(k - 1, Math.floor(mid * k));
    run += lengths[i]!;
  }
  return bins;
}
