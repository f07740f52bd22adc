/**
 * The edges of the exploration view on two canvases under the arcs.
 *
 * - The bulk canvas holds every suggestion and history edge. It is redrawn only when the
 *   edges, the bundling, a layer toggle or the size change, one frame after the arcs so they
 *   show first. Edges are drawn in few strokes: a history edge's segments join the path of
 *   their colour bin on the preferred → other gradient, suggestions join one path per
 *   opacity bin; about 20 strokes of one CSS pixel (a hairline at device pixel ratio 1,
 *   which software rasterisers draw several times faster than wider lines) instead of ~500
 *   gradient strokes (benchmarks/web_render.py).
 * - The highlight canvas above holds the hovered arc's edges, wider; hovering dims the bulk
 *   canvas through CSS opacity instead of redrawing it.
 * - A zoom (d3-zoom's transform, in viewBox units) redraws both under the transform, the
 *   lines as thin as unzoomed; a chart centred on a cluster draws the edges between its
 *   behaviours (those with an end outside have no arc to go to).
 */
import type { Edge } from "../api";
import {
  EQUAL,
  OTHER,
  PREFERRED,
  SUGGESTION,
  mix,
  suggestionAlpha,
  withAlpha,
} from "../lib/colour";
import { type Point, edgePoints, flattenEdge, segmentBins } from "../lib/edges";
import type { RadialLayout } from "../lib/layout";
import type { Tree } from "../lib/tree";

/** A given comparison as an edge: label 1 = a preferred, 0 = b preferred, 0.5 = equal. */
export interface HistoryEdge {
  a: string;
  b: string;
  label: number;
}

export interface EdgeInput {
  tree: Tree;
  layout: RadialLayout;
  /** The coordinate system's width (the SVG viewBox), centred on the origin. */
  viewBox: number;
  /** The drawn square's side in CSS pixels. */
  size: number;
  suggestions: readonly Edge[];
  history: readonly HistoryEdge[];
  showSuggestions: boolean;
  showHistory: boolean;
  beta: number;
  /** The hovered arc (its leaves' edges are highlighted), or null. */
  hover: string | null;
  /** The chart's zoom: a point p of the viewBox is drawn at k · p + (x, y). */
  zoom: { k: number; x: number; y: number };
}

const HISTORY_BINS = 10;
const SUGGESTION_BINS = 6;
const HISTORY_COLOURS = Array.from({ length: HISTORY_BINS }, (_, i) =>
  mix([
    [PREFERRED, HISTORY_BINS - i - 0.5],
    [OTHER, i + 0.5],
  ]),
);
/** What the bulk canvas depends on; a change of any (by identity) redraws it. */
const BULK_KEYS = ["tree", "layout", "size", "suggestions", "history", "showSuggestions", "showHistory", "beta", "zoom"] as const;

interface Layers {
  suggestions: Path2D[];
  history: Path2D[];
  equal: Path2D;
  drawnSuggestions: number;
  drawnHistory: number;
}

function addLine(path: Path2D, line: readonly Point[]): void {
  const [x0, y0] = line[0]!;
  path.moveTo(x0, y0);
  for (let i = 1; i < line.length; i++) path.lineTo(line[i]![0], line[i]![1]);
}

export class EdgeCanvas {
  private input: EdgeInput | null = null;
  /** Flattened bundled curve per edge "a|b", for `linesFor`'s layout and beta. */
  private lines = new Map<string, Point[]>();
  private linesFor: { layout: RadialLayout; beta: number } | null = null;
  private layers: Layers | null = null;
  private layersFor: Pick<EdgeInput, "suggestions" | "history" | "layout" | "beta"> | null = null;
  private drawn: EdgeInput | null = null;
  private frame = 0;

  constructor(
    readonly bulk: HTMLCanvasElement,
    readonly highlight: HTMLCanvasElement,
  ) {}

  update(input: EdgeInput | null): void {
    this.input = input;
    const last = this.drawn;
    const same = last !== null && input !== null && BULK_KEYS.every((k) => last[k] === input[k]);
    if (!same && !this.frame) {
      this.frame = requestAnimationFrame(() => {
        this.frame = 0;
        this.drawBulk();
      });
    }
    this.drawHighlight();
  }

  private line(a: string, b: string): Point[] | null {
    const input = this.input!;
    if (this.linesFor?.layout !== input.layout || this.linesFor.beta !== input.beta) {
      this.lines.clear();
      this.layers = null;
      this.linesFor = { layout: input.layout, beta: input.beta };
    }
    const key = `${a}|${b}`;
    let line = this.lines.get(key);
    if (line) return line;
    const drawn = input.layout.byId;
    if (a === b || !drawn.has(a) || !drawn.has(b)) return null;
    const tree = input.tree;
    line = flattenEdge(edgePoints(tree, input.layout, a, b), input.beta);
    this.lines.set(key, line);
    return line;
  }

  private buildLayers(input: EdgeInput): Layers {
    const layers: Layers = {
      suggestions: Array.from({ length: SUGGESTION_BINS }, () => new Path2D()),
      history: Array.from({ length: HISTORY_BINS }, () => new Path2D()),
      equal: new Path2D(),
      drawnSuggestions: 0,
      drawnHistory: 0,
    };
    for (const e of input.suggestions) {
      const line = this.line(e.a, e.b);
      if (!line) continue;
      const bin = Math.min(SUGGESTION_BINS - 1, Math.max(0, Math.floor(e.score * SUGGESTION_BINS)));
      addLine(layers.suggestions[bin]!, line);
      layers.drawnSuggestions++;
    }
    for (const e of input.history) {
      const line = this.line(e.a, e.b);
      if (!line) continue;
      layers.drawnHistory++;
      if (e.label === 0.5) {
        addLine(layers.equal, line);
        continue;
      }
      // Bins count from the preferred end.
      const bins = segmentBins(line, HISTORY_BINS);
      const flip = e.label < 0.5;
      let open = -1;
      for (let i = 0; i < bins.length; i++) {
        const bin = flip ? HISTORY_BINS - 1 - bins[i]! : bins[i]!;
        const path = layers.history[bin]!;
        if (bin !== open) {
          path.moveTo(line[i]![0], line[i]![1]);
          open = bin;
        }
        path.lineTo(line[i + 1]![0], line[i + 1]![1]);
      }
    }
    return layers;
  }

  /** Sizes a canvas to the chart, clears it, and sets viewBox units (null: nothing to draw). */
  private prepare(canvas: HTMLCanvasElement): CanvasRenderingContext2D | null {
    const input = this.input;
    const dpr = window.devicePixelRatio || 1;
    const px = Math.round((input?.size ?? 0) * dpr);
    if (canvas.width !== px || canvas.height !== px) {
      canvas.width = px;
      canvas.height = px;
    }
    const ctx = canvas.getContext("2d");
    if (!ctx) return null;
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.clearRect(0, 0, px, px);
    if (!input || px === 0) return null;
    const scale = px / input.viewBox;
    const { k, x, y } = input.zoom;
    ctx.setTransform(scale * k, 0, 0, scale * k, px / 2 + scale * x, px / 2 + scale * y);
    ctx.lineCap = "butt";
    ctx.lineJoin = "bevel";
    return ctx;
  }

  private drawBulk(): void {
    const input = this.input;
    const canvas = this.bulk;
    this.drawn = input;
    const ctx = this.prepare(canvas);
    if (!ctx || !input) {
      canvas.dataset.suggestions = "0";
      canvas.dataset.history = "0";
      return;
    }
    const src = this.layersFor;
    const stale = (["suggestions", "history", "layout", "beta"] as const).some((key) => src?.[key] !== input[key]);
    if (!this.layers || stale) {
      this.layers = this.buildLayers(input);
      const { suggestions, history, layout, beta } = input;
      this.layersFor = { suggestions, history, layout, beta };
    }
    const layers = this.layers;
    const cssPixel = input.viewBox / Math.max(1, input.size) / input.zoom.k;
    if (input.showSuggestions) {
      ctx.strokeStyle = SUGGESTION;
      ctx.lineWidth = cssPixel;
      layers.suggestions.forEach((path, bin) => {
        ctx.globalAlpha = Math.min(1, 1.4 * suggestionAlpha((bin + 0.5) / SUGGESTION_BINS));
        ctx.stroke(path);
      });
    }
    if (input.showHistory) {
      ctx.globalAlpha = 0.9;
      ctx.lineWidth = cssPixel;
      layers.history.forEach((path, i) => {
        ctx.strokeStyle = HISTORY_COLOURS[i]!;
        ctx.stroke(path);
      });
      ctx.strokeStyle = EQUAL;
      ctx.setLineDash([9 / input.zoom.k, 7 / input.zoom.k]);
      ctx.stroke(layers.equal);
      ctx.setLineDash([]);
    }
    ctx.globalAlpha = 1;
    // For tests and people reading the DOM: what the canvas shows.
    canvas.dataset.suggestions = String(input.showSuggestions ? layers.drawnSuggestions : 0);
    canvas.dataset.history = String(input.showHistory ? layers.drawnHistory : 0);
    canvas.dataset.drawnAt = String(performance.now());
  }

  private drawHighlight(): void {
    const input = this.input;
    const ctx = this.prepare(this.highlight);
    const node = input?.hover ? input.tree.nodes.get(input.hover) : undefined;
    this.bulk.classList.toggle("dimmed", Boolean(node));
    if (!ctx || !input || !node) return;
    const focus = new Set(node.leaves);
    const touches = (e: { a: string; b: string }) => focus.has(e.a) || focus.has(e.b);
    const k = input.zoom.k;
    if (input.showSuggestions) {
      ctx.lineWidth = 2.4 / k;
      for (const e of input.suggestions) {
        const line = touches(e) && this.line(e.a, e.b);
        if (!line) continue;
        const path = new Path2D();
        addLine(path, line);
        ctx.strokeStyle = withAlpha(SUGGESTION, Math.min(1, 0.35 + suggestionAlpha(e.score)));
        ctx.stroke(path);
      }
    }
    if (input.showHistory) {
      for (const e of input.history) {
        const line = touches(e) && this.line(e.a, e.b);
        if (line) strokeHistory(ctx, line, e.label, k);
      }
    }
  }
}

function strokeHistory(ctx: CanvasRenderingContext2D, line: readonly Point[], label: number, k: number): void {
  const path = new Path2D();
  addLine(path, line);
  ctx.lineWidth = 3.6 / k;
  if (label === 0.5) {
    ctx.setLineDash([9 / k, 7 / k]);
    ctx.strokeStyle = EQUAL;
  } else {
    const p0 = line[0]!;
    const p1 = line[line.length - 1]!;
    const [from, to] = label > 0.5 ? [p0, p1] : [p1, p0];
    const g = ctx.createLinearGradient(from[0], from[1], to[0], to[1]);
    g.addColorStop(0, PREFERRED);
    g.addColorStop(1, OTHER);
    ctx.strokeStyle = g;
  }
  ctx.stroke(path);
  ctx.setLineDash([]);
}
