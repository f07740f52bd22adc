/**
 * Exploration view (SPEC §9, left): the radial hierarchy of the round's behaviours with
 * bundled edges inside — grey suggested comparisons, coloured given comparisons — group
 * tints, a legend with a toggle per edge layer, and the switch of the group clicks fill.
 *
 * This module builds the panel and decides, per render, what must be redrawn. Arcs are SVG
 * (`exploration-arcs.ts`); edges are drawn on canvases under them (`edge-canvas.ts`;
 * benchmarks/web_render.py); pointer, keys and the preview are `exploration-events.ts`.
 */
import { GROUP_COLOURS } from "../lib/colour";
import { attr, h, kbd, memo, s, text } from "./dom";
import { EdgeCanvas } from "./edge-canvas";
import { buildArcs, updateMarks, updateOutline, updateTints } from "./exploration-arcs";
import {
  type CallHandler,
  type Chart,
  type ExplorationData,
  type ExplorationHandlers,
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

  const rebuilt = data.round !== chart.round;
  if (rebuilt) buildArcs(chart, data.round);
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
  const head = h(
    "header",
    { class: "panel-head" },
    h("h2", { id: "exploration-title" }, "Behaviours"),
    subtitle,
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
  const marks = s("path", { class: "uncompared-marks", "aria-hidden": "true" });
  const outline = s("g", { class: "outline", "aria-hidden": "true" });
  svg.append(defs, arcsG, marks, outline);
  const canvas = h("canvas", { class: "chart-canvas chart-edges", "aria-hidden": "true" });
  const highlight = h("canvas", { class: "chart-canvas chart-highlight", "aria-hidden": "true" });
  const box = h("div", { class: "chart-box" }, canvas, highlight, svg);
  const empty = h("div", { class: "chart-empty", role: "status" });
  const wrap = h("div", { class: "chart-wrap" }, box, empty);
  const help = h(
    "p",
    { id: "chart-help", class: "sr-only" },
    "Arcs are behaviours (inner ring) and clusters of them (outer rings). Enter or click " +
      "puts an arc's behaviours in the selected group; Shift adds them instead; Alt or " +
      "right-click fills the other group. Shift with the arrow keys moves between arcs: left " +
      "and right along a ring, up to the enclosing cluster, down into it. The arrow keys " +
      "alone answer the comparison, wherever the focus is.",
  );

  const legend = createLegend((patch) => chart.handlers?.view(patch));

  element.classList.add("panel", "exploration");
  element.setAttribute("aria-labelledby", "exploration-title");
  element.replaceChildren(head, wrap, help, legend.element);

  const chart: Chart = {
    svg,
    edges: new EdgeCanvas(canvas, highlight),
    box,
    wrap,
    empty,
    arcsG,
    marks,
    outline,
    subtitle,
    targetButtons,
    legend,
    // Inside the chart's area: beside it lie the answer buttons and the legend's controls.
    preview: createPreview(document.body, () => wrap.getBoundingClientRect()),
    data: null,
    handlers: null,
    round: null,
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

  targetButtons.A.addEventListener("click", () => call("target", "A"));
  targetButtons.B.addEventListener("click", () => call("target", "B"));
  switchBtn.addEventListener("click", () => call("target", "switch"));

  attachArcEvents(chart, call);
  new ResizeObserver(() => resize(chart)).observe(wrap);
  return chart;
}

function resize(chart: Chart): void {
  const { width, height } = chart.wrap.getBoundingClientRect();
  const size = Math.max(0, Math.floor(Math.min(width, height)));
  if (size === chart.size) return;
  chart.size = size;
  chart.box.style.width = `${size}px`;
  chart.box.style.height = `${size}px`;
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
