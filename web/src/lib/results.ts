/**
 * The finished page's chart of the agent's true return (or target score) per round, as
 * pure geometry: points, the line through the evaluated rounds, and nice axis ticks. The
 * view (`views/results.ts`) only draws what this returns.
 */
import { line } from "d3-shape";

export interface RoundResult {
  round: number;
  /** False for a round without feedback: PPO on the frozen learned reward only. */
  feedback: boolean;
  true_return_mean: number | null;
  true_return_std: number | null;
}

export interface Margin {
  top: number;
  right: number;
  bottom: number;
  left: number;
}

export interface ChartPoint extends RoundResult {
  x: number;
  /** Null for a round that was not evaluated. */
  y: number | null;
}

export interface ChartGeometry {
  points: ChartPoint[];
  /** An SVG path through the evaluated rounds, in round order ("" with none). */
  path: string;
  yTicks: Array<{ value: number; y: number; label: string }>;
  xTicks: Array<{ round: number; x: number }>;
  /** The plotting area, inside the margins. */
  area: { left: number; top: number; right: number; bottom: number };
}

export const CHART_MARGIN: Margin = { top: 12, right: 14, bottom: 26, left: 52 };

/** Round steps (1, 2 or 5 × 10^k) covering [lo, hi] with about `count` intervals. */
export function niceTicks(lo: number, hi: number, count = 4): number[] {
  if (!Number.isFinite(lo) || !Number.isFinite(hi)) return [];
  if (lo === hi) {
    const pad = Math.abs(lo) > 0 ? Math.abs(lo) * 0.1 : 1;
    lo -= pad;
    hi += pad;
  }
  const raw = (hi - lo) / Math.max(1, count);
  const power = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 5, 10].map((m) => m * power).find((s) => s >= raw) ?? 10 * power;
  const first = Math.floor(lo / step) * step;
  const ticks: number[] = [];
  for (let v = first; v <= hi + step * 1e-9; v += step) ticks.push(Number(v.toPrecision(12)));
  if (ticks[ticks.length - 1]! < hi) ticks.push(Number((ticks[ticks.length - 1]! + step).toPrecision(12)));
  return ticks;
}

/** A value as an axis or caption shows it: 3 significant digits, thousands grouped. */
export function formatValue(value: number): string {
  if (value === 0) return "0";
  const abs = Math.abs(value);
  if (abs >= 1000) return Math.round(value).toLocaleString("en");
  return Number(value.toPrecision(3)).toLocaleString("en", { maximumFractionDigits: 3 });
}

/** Where every round's point goes in a `width` × `height` chart (rounds in index order). */
export function chartGeometry(
  rounds: readonly RoundResult[],
  width: number,
  height: number,
  margin: Margin = CHART_MARGIN,
): ChartGeometry {
  const area = {
    left: margin.left,
    top: margin.top,
    right: Math.max(margin.left + 1, width - margin.right),
    bottom: Math.max(margin.top + 1, height - margin.bottom),
  };
  const sorted = [...rounds].sort((a, b) => a.round - b.round);
  const values = sorted.flatMap((r) => (r.true_return_mean === null ? [] : [r.true_return_mean]));
  const ticks = values.length ? niceTicks(Math.min(...values), Math.max(...values)) : [];
  const lo = ticks[0] ?? 0;
  const hi = ticks[ticks.length - 1] ?? 1;
  const y = (v: number) => area.bottom - ((v - lo) / (hi - lo || 1)) * (area.bottom - area.top);
  const first = sorted[0]?.round ?? 0;
  const last = sorted[sorted.length - 1]?.round ?? 0;
  const x = (r: number) =>
    last === first ? (area.left + area.right) / 2 : area.left + ((r - first) / (last - first)) * (area.right - area.left);
  const points = sorted.map((r) => ({
    ...r,
    x: x(r.round),
    y: r.true_return_mean === null ? null : y(r.true_return_mean),
  }));
  const evaluated = points.filter((p): p is ChartPoint & { y: number } => p.y !== null);
  const path =
    line<ChartPoint & { y: number }>()
      .x((p) => p.x)
      .y((p) => p.y)(evaluated) ?? "";
  const every = Math.max(1, Math.ceil(sorted.length / 10));
  return {
    points,
    path,
    yTicks: ticks.map((value) => ({ value, y: y(value), label: formatValue(value) })),
    xTicks: sorted.filter((_, i) => i % every === 0).map((r) => ({ round: r.round, x: x(r.round) })),
    area,
  };
}
