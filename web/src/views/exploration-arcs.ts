/**
 * The exploration view's rings: one SVG arc per drawn tree node (a focusable button), the
 * cluster sizes on the arcs where they fit, their group tints and labels, the marks of
 * behaviours not compared yet, and the hover outline. A selection only retints the arcs
 * whose counts change. Centred on a cluster (issue 40), only its descendants are drawn.
 */
import { arc as d3arc } from "d3-shape";
import { GROUP_COLOURS, groupTint, neutralFill } from "../lib/colour";
import { centreNode } from "../lib/centre";
import { type Arc, midAngle, polar, radialLayout } from "../lib/layout";
import { groupCounts } from "../lib/selection";
import { ancestors } from "../lib/tree";
import type { TreeNode } from "../lib/tree";
import type { RoundData } from "../state";
import { attr, s, text } from "./dom";
import { type Chart, type ExplorationData, VIEWBOX } from "./exploration-chart";

const arcPath = d3arc<Arc>()
  .innerRadius((d) => d.r0)
  .outerRadius((d) => d.r1)
  .startAngle((d) => d.a0)
  .endAngle((d) => d.a1);

/** Font size of the cluster sizes, in viewBox units (about 11 CSS px on a 480 px chart). */
const SIZE_FONT = 23;

/**
 * Draws one arc per node of the round's tree under `centre` (null: the whole round), or
 * clears the chart without a round. The arc of `focusable` (else the first behaviour) is the
 * one Tab reaches.
 */
export function buildArcs(chart: Chart, round: RoundData | null, centre: string | null, focusable?: string): void {
  chart.round = round;
  chart.centre = centre;
  chart.arcEls.clear();
  chart.ancestorIds.clear();
  chart.counts = new Map();
  chart.focusId = null;
  chart.outline.replaceChildren();
  chart.preview.hide();
  if (!round) {
    chart.layout = null;
    chart.arcsG.replaceChildren();
    chart.sizes.replaceChildren();
    text(chart.subtitle, "");
    return;
  }
  const node = centreNode(round.tree, centre);
  const layout = radialLayout(round.tree, { radius: VIEWBOX / 2 - 20, centre: node });
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
  drawSizes(chart);
  for (const leaf of round.tree.leaves) {
    chart.ancestorIds.set(leaf.id, ancestors(leaf).map((n) => n.id));
  }
  const first = (focusable && layout.byId.get(focusable)) || layout.rings[0]?.[0];
  if (first) setFocusable(chart, first.node.id);
  const n = round.tree.leaves.length;
  text(chart.subtitle, `round ${round.round} · ${n} behaviours`);
}

/**
 * Writes the number of behaviours on every cluster's arc wide and deep enough for it at the
 * drawn zoom (the text keeps its size on screen; zoomed in, more of them fit).
 */
export function drawSizes(chart: Chart): void {
  const k = chart.drawn.k;
  const font = SIZE_FONT / k;
  const frag = document.createDocumentFragment();
  for (const a of chart.layout?.arcs ?? []) {
    const n = a.node.leaves.length;
    // A padding node repeats its one child's behaviours: the child's arc has the number.
    if (a.node.isLeaf || n < 2 || a.node.children.length < 2) continue;
    const label = String(n);
    const mid = (a.r0 + a.r1) / 2;
    const along = (a.a1 - a.a0) * mid * k;
    if (along < label.length * SIZE_FONT * 0.62 + 10 || (a.r1 - a.r0) * k < SIZE_FONT * 1.1) continue;
    const [x, y] = polar(midAngle(a), mid);
    const t = s("text", { x: x.toFixed(1), y: y.toFixed(1), "font-size": font.toFixed(2), "data-for": a.node.id });
    t.textContent = label;
    frag.append(t);
  }
  chart.sizes.replaceChildren(frag);
}

/** The one arc reached by Tab (a roving tabindex). */
export function setFocusable(chart: Chart, id: string): void {
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

/** Fills and labels the arcs from the groups; only changed arcs unless `all`. */
export function updateTints(chart: Chart, data: ExplorationData, all: boolean, relabelLeaves: boolean): void {
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

/** A dot inside each behaviour's arc that no judgement has compared yet. */
export function updateMarks(chart: Chart, compared: ReadonlySet<string>): void {
  const layout = chart.layout;
  if (!chart.round || !layout) {
    chart.marks.removeAttribute("d");
    return;
  }
  const n = layout.rings[0]?.length ?? 0;
  const r = layout.discRadius - 7;
  // Sized for the leaves' width on screen (the marks' layer is zoomed).
  const k = chart.drawn.k;
  const dot = Math.max(1, Math.min(3.2, ((Math.PI * r) / Math.max(1, n)) * 0.55 * k)) / k;
  let d = "";
  const f = (v: number) => v.toFixed(k > 4 ? 2 : 1);
  for (const leaf of chart.round.tree.leaves) {
    if (compared.has(leaf.id)) continue;
    const arc = layout.byId.get(leaf.id);
    if (!arc) continue;
    const [x, y] = polar(midAngle(arc), r);
    d += `M${f(x - dot)},${f(y)}a${f(dot)},${f(dot)} 0 1,0 ${f(2 * dot)},0a${f(dot)},${f(dot)} 0 1,0 ${f(-2 * dot)},0`;
  }
  chart.marks.setAttribute("d", d);
}

/** Outlines the hovered arc and its ancestors. */
export function updateOutline(chart: Chart, id: string | null): void {
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
