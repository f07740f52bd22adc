/**
 * The agent's learning as the page shows it (docs/app.md, "The agent learning"): the points
 * the worker writes (`GET /api/sessions/{id}/training`, the `training` event) merged in
 * order (`mergePoints`), the newest in words (`trainingSummary`, `summaryLines`), and the
 * chart of the true return over session time as pure geometry (`curveGeometry`). The view
 * (`views/training.ts`) only draws what these return.
 */
import { line } from "d3-shape";
import type { TrainingPoint } from "../api";
import { type Margin, formatValue, niceTicks } from "./results";

export interface CurvePoint {
  point: TrainingPoint;
  /** Seconds since the session's first point. */
  seconds: number;
  x: number;
  y: number;
}

export interface CurveGeometry {
  /** The evaluated points, in time order. */
  points: CurvePoint[];
  /** An SVG path through them ("" with none). */
  path: string;
  yTicks: Array<{ value: number; y: number; label: string }>;
  xTicks: Array<{ seconds: number; x: number; label: string }>;
  /** The plotting area, inside the margins. */
  area: { left: number; top: number; right: number; bottom: number };
  /** The axes' titles, with their units (`axisTitles`). */
  titles: AxisTitles;
}

export interface AxisTitles {
  x: string;
  y: string;
}

/** What a target env scores, as far as the chart's units go (`AgentTarget` has the
 * per-step score's unit; `GET /api/envs`' `TargetOut` only the episode score's). */
export interface ScoreUnit {
  unit?: string;
  step_unit?: string;
}

export interface TrainingSummary {
  round: number;
  ppoSteps: number;
  pairs: number;
  /** The last refit's held-out accuracy, null without a validation split. */
  valAccuracy: number | null;
  /** PPO steps since the shown round's pool was sampled. */
  poolAge: number;
  /** The newest evaluated true return, null before the first. */
  trueReturn: number | null;
}

export const CURVE_MARGIN: Margin = { top: 8, right: 10, bottom: 32, left: 56 };

/** The axes' titles: session time, and the greedy policy's true return, which in a target
 * env is the sum of the target's per-step scores, in their unit. */
export function axisTitles(target: ScoreUnit | null = null): AxisTitles {
  return {
    x: "session time (m:ss)",
    y: !target ? "true return" : target.step_unit ? `per-step score sum (${target.step_unit})` : "per-step score sum",
  };
}

const time = (p: TrainingPoint) => Date.parse(p.at);
const same = (a: TrainingPoint, b: TrainingPoint) =>
  a.at === b.at && a.round === b.round && a.ppo_steps === b.ppo_steps && a.true_return === b.true_return;

/** `points` with `more` added, each point once, in time order (a point may come both from
 * the read and from the event stream, in either order). */
export function mergePoints(points: readonly TrainingPoint[], more: readonly TrainingPoint[]): TrainingPoint[] {
  const out = [...points];
  for (const p of more) if (!out.some((q) => same(p, q))) out.push(p);
  return out.sort((a, b) => time(a) - time(b));
}

/** The newest round's newest point: its fit and its pool (a round's points carry its own
 * pool's position; the ended round's record may come after the next round's first point),
 * the most PPO steps any point has, and the newest evaluated return. */
export function trainingSummary(points: readonly TrainingPoint[]): TrainingSummary | null {
  if (!points.length) return null;
  const round = Math.max(...points.map((p) => p.round));
  const last = points.filter((p) => p.round === round).pop()!;
  const ppoSteps = Math.max(...points.map((p) => p.ppo_steps));
  const evaluated = points.filter((p) => p.true_return !== null);
  return {
    round,
    ppoSteps,
    pairs: last.pairs,
    valAccuracy: last.reward_val_accuracy,
    poolAge: Math.max(0, ppoSteps - last.pool_steps),
    trueReturn: evaluated[evaluated.length - 1]?.true_return ?? null,
  };
}

const count = (n: number) => Math.round(n).toLocaleString("en");

/** The summary in words: "12,288 PPO steps", "last refit: 14 pairs · 78 % held out
 * right", "pool sampled 12,288 PPO steps ago". */
export function summaryLines(summary: TrainingSummary): { steps: string; refit: string; pool: string } {
  const accuracy =
    summary.valAccuracy === null ? "" : ` · ${Math.round(summary.valAccuracy * 100)} % of held-out pairs right`;
  return {
    steps: `${count(summary.ppoSteps)} PPO steps`,
    refit: `Last refit: ${count(summary.pairs)} ${summary.pairs === 1 ? "pair" : "pairs"}${accuracy}`,
    pool: `Pool sampled ${count(summary.poolAge)} PPO ${summary.poolAge === 1 ? "step" : "steps"} ago`,
  };
}

/** "m:ss" (or "h:mm:ss") for a tick on the session-time axis. */
export function clockLabel(seconds: number): string {
  const s = Math.round(seconds);
  const h = Math.floor(s / 3600);
  const m = Math.floor((s % 3600) / 60);
  const ss = String(s % 60).padStart(2, "0");
  return h ? `${h}:${String(m).padStart(2, "0")}:${ss}` : `${m}:${ss}`;
}

/** Ticks of the session-time axis up to `end` seconds: whole seconds only, each label once
 * (a curve a second long used to read "0:00 0:00 0:00 0:00"). */
export function timeTicks(end: number): number[] {
  if (!(end >= 1)) return [0];
  const ticks = niceTicks(0, end, 4).filter((t) => Number.isInteger(t) && t <= end * 1.0001);
  const seen = new Set<string>();
  return ticks.filter((t) => {
    const label = clockLabel(t);
    if (seen.has(label)) return false;
    seen.add(label);
    return true;
  });
}

/** Where every evaluated point goes in a `width` × `height` chart: x the seconds since the
 * session's first point (refits included), y the true return on nice ticks; `target` names
 * the y axis's unit (`axisTitles`). */
export function curveGeometry(
  points: readonly TrainingPoint[],
  width: number,
  height: number,
  margin: Margin = CURVE_MARGIN,
  target: ScoreUnit | null = null,
): CurveGeometry {
  const area = {
    left: margin.left,
    top: margin.top,
    right: Math.max(margin.left + 1, width - margin.right),
    bottom: Math.max(margin.top + 1, height - margin.bottom),
  };
  const start = points.length ? Math.min(...points.map(time)) : 0;
  const evaluated = points
    .filter((p): p is TrainingPoint & { true_return: number } => p.true_return !== null)
    .map((point) => ({ point, seconds: (time(point) - start) / 1000 }))
    .sort((a, b) => a.seconds - b.seconds);
  const values = evaluated.map((e) => e.point.true_return);
  const yTicks = values.length ? niceTicks(Math.min(...values), Math.max(...values), 3) : [];
  const lo = yTicks[0] ?? 0;
  const hi = yTicks[yTicks.length - 1] ?? 1;
  const y = (v: number) => area.bottom - ((v - lo) / (hi - lo || 1)) * (area.bottom - area.top);
  const end = evaluated[evaluated.length - 1]?.seconds ?? 0;
  const xTicks = timeTicks(end);
  const x = (sec: number) =>
    end > 0 ? area.left + (sec / end) * (area.right - area.left) : (area.left + area.right) / 2;
  const placed = evaluated.map((e) => ({ ...e, x: x(e.seconds), y: y(e.point.true_return) }));
  const path =
    line<CurvePoint>()
      .x((p) => p.x)
      .y((p) => p.y)(placed) ?? "";
  return {
    points: placed,
    path,
    yTicks: yTicks.map((value) => ({ value, y: y(value), label: formatValue(value) })),
    xTicks: evaluated.length ? xTicks.map((sec) => ({ seconds: sec, x: x(sec), label: clockLabel(sec) })) : [],
    area,
    titles: axisTitles(target),
  };
}
