/**
 * What the exploration view's modules share: its data and handlers (the view's API), and the
 * `Chart` that one mounted view keeps between renders — its elements and what is drawn now.
 */
import type { ZoomBehavior, ZoomTransform } from "d3-zoom";
import type { Edge } from "../api";
import type { RadialLayout } from "../lib/layout";
import type { GroupId, Groups } from "../lib/selection";
import type { RoundData, State, ViewSettings } from "../state";
import type { EdgeCanvas, HistoryEdge } from "./edge-canvas";
import type { Legend } from "./legend";
import type { Preview } from "./preview";

export interface ExplorationData {
  round: RoundData | null;
  /** Shown in place of the chart while there is no tree. */
  placeholder: string;
  groups: Groups;
  target: GroupId;
  hover: State["hover"];
  /** The cluster the chart is centred on (null: the whole round). */
  centre: string | null;
  /** The suggestion edges to draw (already the top k). */
  suggestions: readonly Edge[];
  /** How many suggestions exist (the k slider's maximum). */
  maxK: number;
  history: readonly HistoryEdge[];
  compared: ReadonlySet<string>;
  view: ViewSettings;
  clipUrl(clip: string): string;
}

export interface ExplorationHandlers {
  select(click: { id: string; leaves: string[]; isLeaf: boolean; add: boolean }, other: boolean): void;
  /** Centres the chart on a cluster (null: the whole round). */
  centre(id: string | null): void;
  hover(id: string | null): void;
  target(group: GroupId | "switch"): void;
  view(patch: Partial<ViewSettings>): void;
}

/** Side of the SVG viewBox, centred on the disc. */
export const VIEWBOX = 1000;
/** The largest wheel or pinch zoom (d3-zoom's scale extent; `lib/centre.ts` counts on it). */
export const MAX_ZOOM = 16;

/** Calls one of the current handlers (they change with every render). */
export type CallHandler = <K extends keyof ExplorationHandlers>(
  name: K,
  ...args: Parameters<ExplorationHandlers[K]>
) => void;

export interface Chart {
  svg: SVGSVGElement;
  edges: EdgeCanvas;
  box: HTMLDivElement;
  /** The canvases and the SVG, moved by a CSS transform during a zoom gesture. */
  layers: HTMLElement;
  wrap: HTMLElement;
  empty: HTMLElement;
  /** Holds the arcs, labels, marks and outline; d3-zoom's transform applies to it. */
  zoomLayer: SVGGElement;
  arcsG: SVGGElement;
  /** Cluster sizes drawn on the arcs where they fit. */
  sizes: SVGGElement;
  marks: SVGPathElement;
  outline: SVGGElement;
  subtitle: HTMLElement;
  /** The breadcrumb back out of a centred chart, and the zoom's reset. */
  crumbs: HTMLElement;
  resetZoom: HTMLButtonElement;
  zoom: ZoomBehavior<HTMLDivElement, unknown>;
  /** d3-zoom's transform now, in CSS pixels of the square (identity: none). */
  transform: ZoomTransform;
  /** The transform the arcs and edges were drawn at (the gesture's last end). */
  drawn: ZoomTransform;
  targetButtons: Record<GroupId, HTMLButtonElement>;
  legend: Legend;
  preview: Preview;
  // What is drawn now.
  data: ExplorationData | null;
  handlers: ExplorationHandlers | null;
  round: RoundData | null;
  /** The centre the arcs are drawn around (null: the whole round). */
  centre: string | null;
  layout: RadialLayout | null;
  arcEls: Map<string, SVGPathElement>;
  ancestorIds: Map<string, string[]>;
  counts: Map<string, { A: number; B: number }>;
  focusId: string | null;
  /** Side of the drawn square in CSS pixels. */
  size: number;
  hoverTimer: number | undefined;
  pointer: [number, number];
}
