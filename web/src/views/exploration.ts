/**
 * Exploration view (SPEC §9, left): the radial hierarchy of the round's behaviours with
 * bundled edges inside — grey suggested comparisons, coloured given comparisons — group
 * tints, a legend with a toggle per edge layer, and the switch of the group clicks fill.
 *
 * This module builds the panel and decides, per render, what must be redrawn. Arcs are SVG
 * (`exploration-arcs.ts`); edges are drawn on canvases under them (`edge-canvas.ts`;
 * benchmarks/web_render.py); pointer, keys and the preview are `exploration-events.ts`.
 *
 * Issue 40: the chart centres on a cluster (the store's `centre`, with a breadcrumb back
 * out) and zooms with the wheel or a pinch (d3-zoom on the chart's box: during a gesture the
 * drawn arcs and edges move as one picture, at its end both are drawn afresh under the zoom,
 * so the bundles stay); a new centre, round or size starts unzoomed.
 */
import { select } from "d3-selection";
import { type ZoomTransform, zoom, zoomIdentity } from "d3-zoom";
import { crumbs } from "../lib/centre";
import { GROUP_COLOURS } from "../lib/colour";
import { attr, h, kbd, memo, s, text } from "./dom";
import { EdgeCanvas } from "./edge-canvas";
import { buildArcs, drawSizes, updateMarks, updateOutline, updateTints } from "./exploration-arcs";
import {
  type CallHandler,
  type Chart,
  type ExplorationData,
  type ExplorationHandlers,
  MAX_ZOOM,
  VIEWBOX,
} from "./exploration-chart";
import { attachArcEvents, refreshPreview } from "./exploration-events";
import { createLegend } from "./legend";
import { createPreview } from "./preview";

export type { HistoryEdge } from "./edge-canvas";
export type { ExplorationData, ExplorationHandlers } from "./exploration-chart";

const charts = new WeakMap<Element, Chart>();

export function renderExploration(
  element: HTMLElement,
  data: ExplorationData,
  handlers: ExplorationHandlers,
): void {
  const chart = memo(charts, element, () => build(element));
  const prev = chart.data;
  chart.handlers = handlers;
  chart.data = data;

  const rebuilt = data.round !== chart.round || data.centre !== chart.centre;
  if (rebuilt) {
    // A keyboard user keeps the focus in the chart: on the former centre going out, else
    // on the first behaviour.
    const hadFocus = chart.svg.contains(document.activeElement);
    const newRound = data.round?.sid !== chart.round?.sid || data.round?.round !== chart.round?.round;
    buildArcs(chart, data.round, data.centre, newRound ? undefined : (chart.centre ?? undefined));
    if (chart.transform !== zoomIdentity) select(chart.box).call(chart.zoom.transform, zoomIdentity);
    updateCrumbs(chart);
    if (hadFocus && chart.focusId) chart.arcEls.get(chart.focusId)?.focus();
  }
  chart.empty.hidden = data.round !== null;
  text(chart.empty, data.round ? "" : data.placeholder);

  const comparedChanged = prev?.compared !== data.compared;
  if (rebuilt || prev?.groups !== data.groups || comparedChanged) {
    updateTints(chart, data, rebuilt, comparedChanged);
  }
  if (rebuilt || comparedChanged) updateMarks(chart, data.compared);
  if (rebuilt || prev?.hover !== data.hover) {
    updateOutline(chart, data.hover.id);
    refreshPreview(chart);
  } else if (prev?.groups !== data.groups || comparedChanged) refreshPreview(chart);
  drawEdges(chart);
  updateControls(chart, data);
}

/* ---------------------------------------------------------------- skeleton */

function build(element: HTMLElement): Chart {
  const subtitle = h("span", { class: "panel-sub" });
  const targetButtons = {
    A: h("button", { type: "button", class: "target target-A", "aria-pressed": "true" }, "A"),
    B: h("button", { type: "button", class: "target target-B", "aria-pressed": "false" }, "B"),
  };
  const switchBtn = h(
    "button",
    { type: "button", class: "switch", title: "Switch the group that clicks fill (G)" },
    "Switch",
    kbd("G"),
  );
  const crumbList = h("nav", { class: "chart-crumbs", "aria-label": "Chart centre", hidden: true });
  const head = h(
    "header",
    { class: "panel-head" },
    h("h2", { id: "exploration-title" }, "Behaviours"),
    subtitle,
    crumbList,
    h(
      "div",
      { class: "target-switch", role: "group", "aria-label": "Group that clicks fill" },
      h("span", { class: "target-label" }, "Clicks fill"),
      targetButtons.A,
      targetButtons.B,
      switchBtn,
    ),
  );

  const svg = s("svg", {
    class: "chart-svg",
    viewBox: `${-VIEWBOX / 2} ${-VIEWBOX / 2} ${VIEWBOX} ${VIEWBOX}`,
    role: "group",
    "aria-labelledby": "exploration-title",
    "aria-describedby": "chart-help",
  });
  const defs = s(
    "defs",
    {},
    s(
      "pattern",
      {
        id: "hatch-B",
        patternUnits: "userSpaceOnUse",
        width: 7,
        height: 7,
        patternTransform: "rotate(45)",
      },
      s("rect", { width: 7, height: 7, fill: GROUP_COLOURS.B }),
      s("line", { x1: 0, y1: 0, x2: 0, y2: 7, stroke: "#ffffff", "stroke-width": 2.6, "stroke-opacity": 0.75 }),
    ),
  );
  const arcsG = s("g", { class: "arcs" });
  const sizes = s("g", { class: "arc-sizes", "aria-hidden": "true" });
  const marks = s("path", { class: "uncompared-marks", "aria-hidden": "true" });
  const outline = s("g", { class: "outline", "aria-hidden": "true" });
  const zoomLayer = s("g", { class: "zoom-layer" });
  zoomLayer.append(arcsG, sizes, marks, outline);
  svg.append(defs, zoomLayer);
  const canvas = h("canvas", { class: "chart-canvas chart-edges", "aria-hidden": "true" });
  const highlight = h("canvas", { class: "chart-canvas chart-highlight", "aria-hidden": "true" });
  // The layers move together under a CSS transform while a zoom gesture lasts.
  const layers = h("div", { class: "chart-layers" }, canvas, highlight, svg);
  const box = h("div", { class: "chart-box" }, layers);
  const empty = h("div", { class: "chart-empty", role: "status" });
  const resetZoom = h(
    "button",
    { type: "button", class: "small reset-zoom", hidden: true, title: "Back to the unzoomed chart" },
    "Zoom 1×",
  );
  const wrap = h("div", { class: "chart-wrap" }, box, empty, resetZoom);
  const help = h(
    "p",
    { id: "chart-help", class: "sr-only" },
    "Arcs are behaviours (inner ring) and clusters of them (outer rings), each cluster's " +
      "size on its arc. Enter or click puts an arc's behaviours in the selected group; Shift " +
      "adds them instead, and on a behaviour already in a group takes it out; Alt or " +
      "right-click fills the other group. A cluster too big for a group, or C on any " +
      "cluster, becomes the chart's centre; Escape goes back out. Shift with the arrow keys " +
      "moves between arcs: left and right along a ring, up to the enclosing cluster, down " +
      "into it. The arrow keys alone answer the comparison, wherever the focus is.",
  );

  const legend = createLegend((patch) => chart.handlers?.view(patch));

  element.classList.add("panel", "exploration");
  element.setAttribute("aria-labelledby", "exploration-title");
  element.replaceChildren(head, wrap, help, legend.element);

  const chart: Chart = {
    svg,
    edges: new EdgeCanvas(canvas, highlight),
    box,
    layers,
    wrap,
    empty,
    zoomLayer,
    arcsG,
    sizes,
    marks,
    outline,
    subtitle,
    crumbs: crumbList,
    resetZoom,
    zoom: zoom<HTMLDivElement, unknown>(),
    transform: zoomIdentity,
    drawn: zoomIdentity,
    targetButtons,
    legend,
    // Inside the chart's area: beside it lie the answer buttons and the legend's controls.
    preview: createPreview(document.body, () => wrap.getBoundingClientRect()),
    data: null,
    handlers: null,
    round: null,
    centre: null,
    layout: null,
    arcEls: new Map(),
    ancestorIds: new Map(),
    counts: new Map(),
    focusId: null,
    size: 0,
    hoverTimer: undefined,
    pointer: [0, 0],
  };

  const call: CallHandler = (name, ...args) =>
    (chart.handlers![name] as (...a: typeof args) => void)(...args);

  chart.zoom
    .scaleExtent([1, MAX_ZOOM])
    .on("zoom", (e: { transform: ZoomTransform }) => moveZoom(chart, e.transform))
    .on("end", () => settleZoom(chart));
  // Double-clicks stay clicks (two fills), not a zoom.
  select(box).call(chart.zoom).on("dblclick.zoom", null);
  resetZoom.addEventListener("click", () => select(box).call(chart.zoom.transform, zoomIdentity));
  crumbList.addEventListener("click", (e) => {
    const id = (e.target as Element).closest<HTMLElement>("[data-centre]")?.dataset.centre;
    if (id !== undefined) call("centre", id === "" ? null : id);
  });

  targetButtons.A.addEventListener("click", () => call("target", "A"));
  targetButtons.B.addEventListener("click", () => call("target", "B"));
  switchBtn.addEventListener("click", () => call("target", "switch"));

  attachArcEvents(chart, call);
  new ResizeObserver(() => resize(chart)).observe(wrap);
  return chart;
}

/**
 * A step of a zoom gesture (d3-zoom's transform `t`, in CSS pixels of the chart's square):
 * the drawn layers move under a CSS transform from the zoom they were drawn at, which the
 * compositor applies without repainting a path (benchmarks/web_render.py: a repaint of the
 * arcs and edges per step took ~30 ms at 1,000 behaviours).
 */
function moveZoom(chart: Chart, t: ZoomTransform): void {
  chart.transform = t;
  const d = chart.drawn;
  const r = t.k / d.k;
  const moved = t.k !== d.k || t.x !== d.x || t.y !== d.y;
  chart.layers.style.transform = moved ? `translate(${t.x - r * d.x}px, ${t.y - r * d.y}px) scale(${r})` : "";
  chart.wrap.dataset.zoom = t.k.toFixed(2);
  chart.resetZoom.hidden = t.k === 1;
  chart.preview.hide();
}

/** The gesture ended: the arcs and edges are drawn afresh at its zoom, sharp. */
function settleZoom(chart: Chart): void {
  chart.drawn = chart.transform;
  const z = viewBoxZoom(chart);
  const identity = z.k === 1 && z.x === 0 && z.y === 0;
  chart.zoomLayer.setAttribute("transform", identity ? "" : `translate(${z.x},${z.y}) scale(${z.k})`);
  chart.layers.style.transform = "";
  drawSizes(chart);
  if (chart.data) updateMarks(chart, chart.data.compared);
  chart.wrap.dataset.settledAt = String(performance.now());
  drawEdges(chart);
}

/** The drawn zoom in viewBox units: a point p of the layout is drawn at k · p + (x, y). */
function viewBoxZoom(chart: Chart): { k: number; x: number; y: number } {
  const d = chart.drawn;
  const scale = chart.size / VIEWBOX;
  if (scale <= 0) return { k: 1, x: 0, y: 0 };
  const c = chart.size / 2;
  return { k: d.k, x: (d.x + (d.k - 1) * c) / scale, y: (d.y + (d.k - 1) * c) / scale };
}

/** The breadcrumb of a centred chart, in the panel's head in place of the round's line: the
 * whole round, the clusters on the way, the centre. */
function updateCrumbs(chart: Chart): void {
  const round = chart.round;
  const path = round ? crumbs(round.tree, chart.centre) : [];
  chart.crumbs.hidden = path.length < 2;
  chart.subtitle.hidden = !chart.crumbs.hidden;
  if (chart.crumbs.hidden || !round) {
    chart.crumbs.replaceChildren();
    return;
  }
  const items = path.map((node, i) => {
    const n = node.leaves.length;
    const name = i === 0 ? `All ${n}` : i === path.length - 1 ? `${n} behaviours` : String(n);
    if (i === path.length - 1) return h("li", {}, h("span", { "aria-current": "location" }, name));
    const label = i === 0 ? `Back to all ${n} behaviours` : `Back out to the cluster of ${n} behaviours`;
    return h(
      "li",
      {},
      h("button", { type: "button", class: "link", "data-centre": i === 0 ? "" : node.id, "aria-label": label }, name),
    );
  });
  chart.crumbs.replaceChildren(h("ol", {}, ...items));
}

function resize(chart: Chart): void {
  const { width, height } = chart.wrap.getBoundingClientRect();
  const size = Math.max(0, Math.floor(Math.min(width, height)));
  if (size === chart.size) return;
  chart.size = size;
  chart.box.style.width = `${size}px`;
  chart.box.style.height = `${size}px`;
  // The zoom is in pixels of the old size: the chart starts unzoomed at the new one.
  chart.zoom.translateExtent([
    [0, 0],
    [size, size],
  ]);
  if (chart.transform !== zoomIdentity) select(chart.box).call(chart.zoom.transform, zoomIdentity);
  drawEdges(chart);
}

/* ---------------------------------------------------------------- edges */

function drawEdges(chart: Chart): void {
  const data = chart.data;
  const round = chart.round;
  const layout = chart.layout;
  chart.edges.update(
    data && round && layout
      ? {
          tree: round.tree,
          layout,
          viewBox: VIEWBOX,
          size: chart.size,
          suggestions: data.suggestions,
          history: data.history,
          showSuggestions: data.view.showSuggestions,
          showHistory: data.view.showHistory,
          beta: data.view.beta,
          hover: data.hover.id,
          zoom: viewBoxZoom(chart),
        }
      : null,
  );
}

/* ---------------------------------------------------------------- controls */

function updateControls(chart: Chart, data: ExplorationData): void {
  for (const g of ["A", "B"] as const) {
    attr(chart.targetButtons[g], "aria-pressed", String(data.target === g));
    attr(chart.targetButtons[g], "aria-label", `Clicks fill group ${g}`);
  }
  chart.wrap.dataset.target = data.target;
  chart.legend.update(data.view, data.maxK, data.suggestions.length, data.history);
}
