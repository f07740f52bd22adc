/**
 * Exploration view (SPEC §9, left): the radial hierarchy of the round's behaviours with
 * bundled edges inside — grey suggested comparisons, coloured given comparisons — group
 * tints, a legend with a toggle per edge layer, and the switch of the group clicks fill.
 *
 * Arcs are SVG (focusable buttons; a selection only retints the arcs whose counts change);
 * edges are drawn on canvases under them (`edge-canvas.ts`; benchmarks/web_render.py).
 */
import { arc as d3arc } from "d3-shape";
import type { Edge } from "../api";
import { GROUP_COLOURS, groupTint, neutralFill } from "../lib/colour";
import { type Arc, type RadialLayout, midAngle, neighbourArc, polar, radialLayout } from "../lib/layout";
import { type GroupId, type Groups, groupCounts } from "../lib/selection";
import { ancestors } from "../lib/tree";
import type { TreeNode } from "../lib/tree";
import type { RoundData, State, ViewSettings } from "../state";
import { attr, h, kbd, memo, s, text } from "./dom";
import { EdgeCanvas, type HistoryEdge } from "./edge-canvas";
import { type Legend, createLegend } from "./legend";
import { type Preview, createPreview, previewContent } from "./preview";

export type { HistoryEdge } from "./edge-canvas";

export interface ExplorationData {
  round: RoundData | null;
  /** Shown in place of the chart while there is no tree. */
  placeholder: string;
  groups: Groups;
  target: GroupId;
  hover: State["hover"];
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
  select(click: { leaves: string[]; isLeaf: boolean; add: boolean }, other: boolean): void;
  hover(id: string | null): void;
  target(group: GroupId | "switch"): void;
  view(patch: Partial<ViewSettings>): void;
}

const VIEWBOX = 1000;
const HOVER_DELAY_MS = 90;

interface Chart {
  svg: SVGSVGElement;
  edges: EdgeCanvas;
  box: HTMLElement;
  wrap: HTMLElement;
  empty: HTMLElement;
  arcsG: SVGGElement;
  marks: SVGPathElement;
  outline: SVGGElement;
  subtitle: HTMLElement;
  targetButtons: Record<GroupId, HTMLButtonElement>;
  legend: Legend;
  preview: Preview;
  // What is drawn now.
  data: ExplorationData | null;
  handlers: ExplorationHandlers | null;
  round: RoundData | null;
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
      "right-click fills the other group. Arrow keys move between arcs: left and right along " +
      "a ring, up to the enclosing cluster, down into it.",
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
    preview: createPreview(),
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

  const call = <K extends keyof ExplorationHandlers>(
    name: K,
    ...args: Parameters<ExplorationHandlers[K]>
  ) => (chart.handlers![name] as (...a: typeof args) => void)(...args);

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

/* ---------------------------------------------------------------- arcs */

const arcPath = d3arc<Arc>()
  .innerRadius((d) => d.r0)
  .outerRadius((d) => d.r1)
  .startAngle((d) => d.a0)
  .endAngle((d) => d.a1);

function buildArcs(chart: Chart, round: RoundData | null): void {
  chart.round = round;
  chart.arcEls.clear();
  chart.ancestorIds.clear();
  chart.counts = new Map();
  chart.focusId = null;
  chart.outline.replaceChildren();
  chart.preview.hide();
  if (!round) {
    chart.layout = null;
    chart.arcsG.replaceChildren();
    text(chart.subtitle, "");
    return;
  }
  const layout = radialLayout(round.tree, { radius: VIEWBOX / 2 - 20 });
  chart.layout = layout;
  const frag = document.createDocumentFragment();
  for (const a of layout.arcs) {
    const node = a.node;
    const el = document.createElementNS("http://www.w3.org/2000/svg", "path");
    el.setAttribute("d", arcPath(a) ?? "");
    el.setAttribute("class", node.isLeaf ? "arc leaf" : "arc node");
    el.setAttribute("data-id", node.id);
    el.setAttribute("role", "button");
    el.setAttribute("tabindex", "-1");
    el.setAttribute("fill", neutralFill(a.ring));
    frag.append(el);
    chart.arcEls.set(node.id, el);
  }
  chart.arcsG.replaceChildren(frag);
  for (const leaf of round.tree.leaves) {
    chart.ancestorIds.set(leaf.id, ancestors(leaf).map((n) => n.id));
  }
  const first = layout.rings[0]?.[0];
  if (first) setFocusable(chart, first.node.id);
  const n = round.tree.leaves.length;
  text(chart.subtitle, `round ${round.round + 1} · ${n} behaviours · ${layout.levels} levels`);
}

function setFocusable(chart: Chart, id: string): void {
  if (chart.focusId) chart.arcEls.get(chart.focusId)?.setAttribute("tabindex", "-1");
  chart.focusId = id;
  chart.arcEls.get(id)?.setAttribute("tabindex", "0");
}

function arcLabel(node: TreeNode, c: { A: number; B: number } | undefined, compared: ReadonlySet<string>): string {
  const n = node.leaves.length;
  if (node.isLeaf || n === 1) {
    // A padding node (one child) stands for the same single behaviour one level up.
    const id = node.leaves[0]!;
    const where = c?.A ? ", in group A" : c?.B ? ", in group B" : "";
    const level = node.isLeaf ? "" : `, level ${node.level}`;
    return `behaviour ${id}${level}${where}${compared.has(id) ? "" : ", not compared yet"}`;
  }
  const parts = [`cluster of ${n} behaviours, level ${node.level}`];
  if (c?.A) parts.push(`${c.A} in group A`);
  if (c?.B) parts.push(`${c.B} in group B`);
  return parts.join(", ");
}

function updateTints(chart: Chart, data: ExplorationData, all: boolean, relabelLeaves: boolean): void {
  if (!chart.round || !chart.layout) return;
  const next = groupCounts(data.groups, (leaf) => chart.ancestorIds.get(leaf) ?? []);
  // Only arcs whose counts changed are touched (a selection update stays O(selected · depth)).
  const ids = all ? [...chart.arcEls.keys()] : [...new Set([...chart.counts.keys(), ...next.keys()])];
  for (const id of ids) {
    const el = chart.arcEls.get(id);
    const a = chart.layout.byId.get(id);
    if (!el || !a) continue;
    const c = next.get(id);
    const node = a.node;
    const fill = node.isLeaf
      ? c?.A
        ? GROUP_COLOURS.A
        : c?.B
          ? "url(#hatch-B)"
          : neutralFill(0)
      : groupTint(neutralFill(a.ring), c?.A ?? 0, c?.B ?? 0, node.leaves.length);
    attr(el, "fill", fill);
    attr(el, "aria-label", arcLabel(node, c, data.compared));
  }
  if (relabelLeaves && !all) {
    for (const a of chart.layout.arcs) {
      if (a.node.leaves.length !== 1) continue;
      const el = chart.arcEls.get(a.node.id);
      if (el) attr(el, "aria-label", arcLabel(a.node, next.get(a.node.id), data.compared));
    }
  }
  chart.counts = next;
}

function updateMarks(chart: Chart, compared: ReadonlySet<string>): void {
  const layout = chart.layout;
  if (!chart.round || !layout) {
    chart.marks.removeAttribute("d");
    return;
  }
  const n = chart.round.tree.leaves.length;
  const r = layout.discRadius - 7;
  const dot = Math.max(1, Math.min(3.2, ((Math.PI * r) / Math.max(1, n)) * 0.55));
  let d = "";
  for (const leaf of chart.round.tree.leaves) {
    if (compared.has(leaf.id)) continue;
    const arc = layout.byId.get(leaf.id);
    if (!arc) continue;
    const [x, y] = polar(midAngle(arc), r);
    d += `M${(x - dot).toFixed(1)},${y.toFixed(1)}a${dot},${dot} 0 1,0 ${2 * dot},0a${dot},${dot} 0 1,0 ${-2 * dot},0`;
  }
  chart.marks.setAttribute("d", d);
}

function updateOutline(chart: Chart, id: string | null): void {
  chart.outline.replaceChildren();
  const layout = chart.layout;
  if (!id || !layout) return;
  const a = layout.byId.get(id);
  if (!a) return;
  const nodes = [a.node, ...ancestors(a.node)];
  for (const n of nodes) {
    const arc = layout.byId.get(n.id);
    if (!arc) continue;
    chart.outline.append(
      s("path", { d: arcPath(arc) ?? "", class: n === a.node ? "hover-arc" : "hover-ancestor" }),
    );
  }
}

/* ---------------------------------------------------------------- events */

function attachArcEvents(
  chart: Chart,
  call: <K extends keyof ExplorationHandlers>(name: K, ...args: Parameters<ExplorationHandlers[K]>) => void,
): void {
  const svg = chart.svg;
  const arcOf = (target: EventTarget | null): Arc | null => {
    const el = (target as Element | null)?.closest?.("[data-id]");
    const id = el?.getAttribute("data-id");
    return (id && chart.layout?.byId.get(id)) || null;
  };
  const select = (a: Arc, add: boolean, other: boolean) =>
    call("select", { leaves: [...a.node.leaves], isLeaf: a.node.isLeaf, add }, other);

  svg.addEventListener("click", (e) => {
    const a = arcOf(e.target);
    if (!a) return;
    setFocusable(chart, a.node.id);
    select(a, e.shiftKey || e.ctrlKey || e.metaKey, e.altKey);
  });
  svg.addEventListener("contextmenu", (e) => {
    const a = arcOf(e.target);
    if (!a) return;
    e.preventDefault();
    select(a, e.shiftKey || e.ctrlKey || e.metaKey, true);
  });
  svg.addEventListener("pointermove", (e) => {
    chart.pointer = [e.clientX, e.clientY];
    chart.preview.move(e.clientX, e.clientY);
  });
  svg.addEventListener("pointerover", (e) => {
    const a = arcOf(e.target);
    if (!a) return;
    chart.pointer = [e.clientX, e.clientY];
    hoverArc(chart, a, call);
  });
  svg.addEventListener("pointerleave", () => {
    window.clearTimeout(chart.hoverTimer);
    chart.preview.hide();
    call("hover", null);
  });
  svg.addEventListener("focusin", (e) => {
    const a = arcOf(e.target);
    if (!a) return;
    const r = (e.target as Element).getBoundingClientRect();
    chart.pointer = [r.right, r.top + r.height / 2];
    hoverArc(chart, a, call);
  });
  svg.addEventListener("focusout", (e) => {
    if (svg.contains(e.relatedTarget as Node | null)) return;
    chart.preview.hide();
    call("hover", null);
  });
  svg.addEventListener("keydown", (e) => {
    const a = arcOf(e.target);
    if (!a || !chart.layout) return;
    if (e.key === "Enter" || e.key === " ") {
      e.preventDefault();
      select(a, e.shiftKey || e.ctrlKey || e.metaKey, e.altKey);
      return;
    }
    const next = neighbourArc(chart.layout, a, e.key);
    if (next === undefined) return;
    e.preventDefault();
    e.stopPropagation();
    if (!next) return;
    setFocusable(chart, next.node.id);
    chart.arcEls.get(next.node.id)?.focus();
  });
}

function hoverArc(
  chart: Chart,
  a: Arc,
  call: <K extends keyof ExplorationHandlers>(name: K, ...args: Parameters<ExplorationHandlers[K]>) => void,
): void {
  call("hover", a.node.id);
  window.clearTimeout(chart.hoverTimer);
  chart.hoverTimer = window.setTimeout(() => {
    if (chart.data?.hover.id !== a.node.id) return;
    showPreview(chart, a.node);
  }, HOVER_DELAY_MS);
}

/* ---------------------------------------------------------------- edges, preview */

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

function showPreview(chart: Chart, node: TreeNode): void {
  const data = chart.data;
  if (!chart.round || !data) return;
  const content = previewContent(chart.round, node, chart.counts.get(node.id), data.compared, data.clipUrl);
  chart.preview.show(content, chart.pointer[0], chart.pointer[1]);
}

/** Keeps a visible preview's text in step with the selection (its videos keep playing). */
function refreshPreview(chart: Chart): void {
  const id = chart.data?.hover.id;
  const node = id ? chart.round?.tree.nodes.get(id) : undefined;
  if (!node || chart.preview.element.hidden) return;
  showPreview(chart, node);
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
