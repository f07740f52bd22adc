/**
 * The exploration view's interaction: clicks, the context menu and keys on the arcs select
 * groups, centre the chart and move the focus; pointer and focus show the hovered node and,
 * after a short delay, its preview (the tooltip with clips). Wheel and pinch are d3-zoom's
 * (`exploration.ts`).
 */
import { canCentre, outward } from "../lib/centre";
import { type Arc, arcAt, neighbourArc } from "../lib/layout";
import type { TreeNode } from "../lib/tree";
import { setFocusable } from "./exploration-arcs";
import type { CallHandler, Chart } from "./exploration-chart";
import { previewContent } from "./preview";

const HOVER_DELAY_MS = 90;

/** Listens on the chart's SVG once; every listener reads the chart's current state. */
export function attachArcEvents(chart: Chart, call: CallHandler): void {
  const svg = chart.svg;
  const arcOf = (target: EventTarget | null): Arc | null => {
    const el = (target as Element | null)?.closest?.("[data-id]");
    const id = el?.getAttribute("data-id");
    return (id && chart.layout?.byId.get(id)) || null;
  };
  /** The arc drawn under a pointer event, also when the event reached the SVG itself (a
   * right-click's `contextmenu` did, now and then, right after a load: issue 23). */
  const arcUnder = (e: MouseEvent): Arc | null => {
    const hit = arcOf(e.target);
    const m = chart.zoomLayer.getScreenCTM(); // the layout's coordinates, zoomed
    if (hit || !chart.layout || !m) return hit;
    const p = new DOMPoint(e.clientX, e.clientY).matrixTransform(m.inverse());
    return arcAt(chart.layout, p.x, p.y);
  };
  /** The arc a right button went down on: the context menu that follows fills with it. */
  let pressed: Arc | null = null;
  const select = (a: Arc, add: boolean, other: boolean) =>
    call("select", { id: a.node.id, leaves: [...a.node.leaves], isLeaf: a.node.isLeaf, add }, other);

  svg.addEventListener("click", (e) => {
    const a = arcUnder(e);
    if (!a) return;
    setFocusable(chart, a.node.id);
    select(a, e.shiftKey || e.ctrlKey || e.metaKey, e.altKey);
  });
  svg.addEventListener("pointerdown", (e) => {
    pressed = e.button === 2 ? arcUnder(e) : null;
  });
  // Right-click fills the other group. The menu comes after the press (Linux, on the press;
  // Windows, on the release); either way the arc pressed is the one meant.
  svg.addEventListener("contextmenu", (e) => {
    const a = arcOf(e.target) ?? pressed ?? arcUnder(e);
    pressed = null;
    if (!a) return;
    e.preventDefault();
    setFocusable(chart, a.node.id);
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
    // C centres the chart on the focused cluster; Escape or Backspace goes one step out.
    const plain = !e.ctrlKey && !e.metaKey && !e.altKey;
    if (plain && (e.key === "c" || e.key === "C") && canCentre(a.node)) {
      e.preventDefault();
      e.stopPropagation();
      call("centre", a.node.id);
      return;
    }
    if (plain && (e.key === "Escape" || e.key === "Backspace") && chart.round && chart.centre !== null) {
      e.preventDefault();
      e.stopPropagation();
      call("centre", outward(chart.round.tree, chart.centre));
      return;
    }
    // Shift + arrows move between arcs; plain arrows are the page's answer keys
    if (e.key.startsWith("Arrow") && !e.shiftKey) return;
    const next = neighbourArc(chart.layout, a, e.key);
    if (next === undefined) return;
    e.preventDefault();
    e.stopPropagation();
    if (!next) return;
    setFocusable(chart, next.node.id);
    chart.arcEls.get(next.node.id)?.focus();
  });
}

function hoverArc(chart: Chart, a: Arc, call: CallHandler): void {
  call("hover", a.node.id);
  window.clearTimeout(chart.hoverTimer);
  chart.hoverTimer = window.setTimeout(() => {
    if (chart.data?.hover.id !== a.node.id) return;
    showPreview(chart, a.node);
  }, HOVER_DELAY_MS);
}

function showPreview(chart: Chart, node: TreeNode): void {
  const data = chart.data;
  if (!chart.round || !data) return;
  const content = previewContent(chart.round, node, chart.counts.get(node.id), data.compared, data.clipUrl);
  chart.preview.show(content, chart.pointer[0], chart.pointer[1]);
}

/** Keeps a visible preview's text in step with the selection (its videos keep playing). */
export function refreshPreview(chart: Chart): void {
  const id = chart.data?.hover.id;
  const node = id ? chart.round?.tree.nodes.get(id) : undefined;
  if (!node || chart.preview.element.hidden) return;
  showPreview(chart, node);
}
