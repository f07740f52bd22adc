/**
 * The agent learning (docs/app.md): a small chart of the greedy policy's true return over
 * the session's time, PPO steps so far, the last refit (pairs, held-out accuracy) and the
 * shown pool's age in PPO steps. The open page shows it under the comparison while a
 * continuous session trains (`renderTraining`); the finished page draws the same chart
 * (`drawCurve`). Geometry and words come from `lib/training.ts`.
 */
import type { SessionState, TrainingPoint } from "../api";
import { formatValue } from "../lib/results";
import {
  CURVE_MARGIN,
  type CurveGeometry,
  type ScoreUnit,
  curveGeometry,
  summaryLines,
  trainingSummary,
} from "../lib/training";
import { h, memo, s, text } from "./dom";

export interface TrainingData {
  session: SessionState | null;
  points: readonly TrainingPoint[];
  /** The session's target, when its env is one: the chart's unit (`GET /api/envs`). */
  target?: ScoreUnit | null;
}

interface View {
  chart: SVGSVGElement;
  steps: HTMLElement;
  refit: HTMLElement;
  pool: HTMLElement;
  empty: HTMLElement;
}

const views = new WeakMap<Element, View>();
/** The open page's chart, in SVG units (before the page knows its width). */
export const PANEL_CHART = { width: 360, height: 110 };

const SHOWN: ReadonlySet<SessionState["phase"]> = new Set(["ready", "training", "preparing"]);

export function renderTraining(element: HTMLElement, data: TrainingData): void {
  const s = data.session;
  element.hidden = !s || s.settings.training !== "continuous" || !SHOWN.has(s.phase);
  if (element.hidden) return;
  const view = memo(views, element, () => build(element));
  const summary = trainingSummary(data.points);
  view.empty.hidden = summary !== null;
  for (const line of [view.steps, view.refit, view.pool]) line.hidden = summary === null;
  if (summary) {
    const lines = summaryLines(summary);
    text(view.steps, lines.steps);
    text(view.refit, lines.refit);
    text(view.pool, lines.pool);
  }
  // Drawn at the width it is shown (the panel is wider in pairwise mode), text unscaled.
  const shown = Math.round(view.chart.getBoundingClientRect().width);
  const size = { ...PANEL_CHART, width: shown > 0 ? shown : PANEL_CHART.width };
  drawCurve(view.chart, data.points, size, data.target ?? null);
}

/** Draw the true return over session time into `svg` (`width` × `height` SVG units), its
 * axes titled with their units (`target`: a target env's score unit). */
export function drawCurve(
  svg: SVGSVGElement,
  points: readonly TrainingPoint[],
  size: { width: number; height: number },
  target: ScoreUnit | null = null,
): CurveGeometry {
  const g = curveGeometry(points, size.width, size.height, CURVE_MARGIN, target);
  const a = g.area;
  const children: SVGElement[] = [];
  const middle = (a.top + a.bottom) / 2;
  children.push(
    s("text", { class: "axis-label x", x: (a.left + a.right) / 2, y: size.height - 3 }, g.titles.x),
    s(
      "text",
      { class: "axis-label y", x: 11, y: middle, transform: `rotate(-90 11 ${middle})` },
      g.titles.y,
    ),
  );
  for (const t of g.yTicks) {
    children.push(s("line", { class: "grid", x1: a.left, x2: a.right, y1: t.y, y2: t.y }));
    children.push(s("text", { class: "tick y", x: a.left - 6, y: t.y, dy: "0.32em" }, t.label));
  }
  for (const t of g.xTicks) {
    children.push(s("text", { class: "tick x", x: t.x, y: a.bottom + 14 }, t.label));
  }
  children.push(s("line", { class: "axis", x1: a.left, x2: a.right, y1: a.bottom, y2: a.bottom }));
  if (g.path) children.push(s("path", { class: "line", d: g.path }));
  for (const p of g.points) {
    const label =
      `${p.point.ppo_steps.toLocaleString("en")} PPO steps (round ${p.point.round}): ` +
      `${g.titles.y} ${formatValue(p.point.true_return ?? 0)}`;
    children.push(
      s("circle", { class: "curve-point", cx: p.x, cy: p.y, r: 3, "data-steps": p.point.ppo_steps }, s("title", {}, label)),
    );
  }
  svg.replaceChildren(...children);
  svg.setAttribute("viewBox", `0 0 ${size.width} ${size.height}`);
  svg.setAttribute(
    "aria-label",
    g.points.length
      ? `${capitalise(g.titles.y)} over session time: ${g.points
          .map((p) => `${formatValue(p.point.true_return ?? 0)} at ${p.point.ppo_steps.toLocaleString("en")} PPO steps`)
          .join(", ")}`
      : `${capitalise(g.titles.y)} over session time: not measured yet`,
  );
  return g;
}

const capitalise = (words: string) => words.charAt(0).toUpperCase() + words.slice(1);

function build(element: HTMLElement): View {
  element.classList.add("panel", "training-panel");
  element.setAttribute("aria-label", "The agent learning");
  const chart = s("svg", { class: "return-chart training-chart", role: "img" });
  const steps = h("p", { class: "training-steps" });
  const refit = h("p", { class: "training-line" });
  const pool = h("p", { class: "training-line" });
  const empty = h("p", { class: "training-line muted" }, "PPO starts with your first answer.");
  element.replaceChildren(
    h(
      "div",
      { class: "training-text" },
      h("h3", { class: "chart-title" }, "The agent learning"),
      steps,
      refit,
      pool,
      empty,
    ),
    h("div", { class: "training-plot" }, chart),
  );
  return { chart, steps, refit, pool, empty };
}
