/**
 * The finished page's numbers: the agent's evaluation in words (`scoreLines`, `scoreText`:
 * a target env's episode score in its unit first, the per-step sum beside it) and the chart
 * of a score per round (`chartSeries`) as pure geometry: points, the line through the
 * evaluated rounds, nice axis ticks and the target's threshold. The view
 * (`views/results.ts`) only draws what these return.
 */
import { line } from "d3-shape";
import type { AgentOut } from "../api";

export interface RoundResult {
  round: number;
  /** False for a round without feedback: PPO on the frozen learned reward only. */
  feedback: boolean;
  /** What the chart plots; null for a round that was not evaluated. */
  value: number | null;
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
  /** Where the `reference` value (a target's threshold) lies; null without one. */
  reference: { value: number; y: number } | null;
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

/** A value as an axis or caption shows it: 3 significant digits, thousands grouped (as
 * `agent_package.format_value` writes it in the zip's README). */
export function formatValue(value: number): string {
  if (value === 0) return "0";
  const abs = Math.abs(value);
  if (abs >= 1000) return Math.round(value).toLocaleString("en");
  return Number(value.toPrecision(3)).toLocaleString("en", { maximumSignificantDigits: 3 });
}

/** Decimals of `value` written to `digits` significant figures (0 for a whole number). */
function decimalsAt(value: number, digits: number): number {
  const rounded = Number(Math.abs(value).toPrecision(digits));
  return rounded === 0 ? 0 : Math.max(0, digits - 1 - Math.floor(Math.log10(rounded)));
}

/**
 * "mean ± sd" (the sd left out when unknown), both to one decimal place: the sd's second
 * significant figure, but no finer than the mean's third ("0.140 ± 0.001", not
 * "0.14 ± 0.000621"; "184 ± 3", "41.5 ± 3.2"; issue 40). `agent_file.text.mean_sd` writes
 * the zip's README the same way.
 */
export function meanSd(mean: number, sd: number | null | undefined): string {
  if (sd === null || sd === undefined) return formatValue(mean);
  if (sd === 0 || !Number.isFinite(sd) || !Number.isFinite(mean)) return `${formatValue(mean)} ± ${formatValue(sd)}`;
  const places = Math.abs(mean) >= 1000 ? 0 : Math.min(decimalsAt(sd, 2), mean === 0 ? 20 : decimalsAt(mean, 3));
  const fixed = (v: number) =>
    v.toLocaleString("en", { minimumFractionDigits: places, maximumFractionDigits: places });
  // an sd below the last place shown is one unit of it, never "± 0.000"
  return `${fixed(mean)} ± ${fixed(Math.max(Math.abs(sd), 10 ** -places))}`;
}

export function capitalise(words: string): string {
  return words.charAt(0).toUpperCase() + words.slice(1);
}

type Agent = Pick<
  AgentOut,
  "measure" | "true_return_mean" | "true_return_std" | "target" | "target_score_mean" | "target_score_std" | "rounds"
>;

/** The evaluation as the page shows it: `label` `value` (`goal`), then `detail` below. */
export interface ScoreLines {
  /** "Backward turns per episode", or "True return". */
  label: string;
  /** "0.23 ± 0.05" */
  value: string;
  /** "threshold 1 · stretch 2" for a target; null otherwise. */
  goal: string | null;
  /** A target's per-step sum, "per-step sum 184 ± 2.62 rad/s"; null otherwise. */
  detail: string | null;
}

/** The agent's last evaluation, or null when it was not evaluated. A target env's episode
 * score leads; an agent published before episode scores were recorded shows its per-step
 * sum under its `measure`. */
export function scoreLines(agent: Agent): ScoreLines | null {
  const t = agent.target;
  const perStep =
    agent.true_return_mean === null ? null : meanSd(agent.true_return_mean, agent.true_return_std);
  if (t && agent.target_score_mean !== null) {
    return {
      label: `${capitalise(t.unit)} per episode`,
      value: meanSd(agent.target_score_mean, agent.target_score_std),
      goal: `threshold ${formatValue(t.threshold)} · stretch ${formatValue(t.stretch)}`,
      detail: perStep === null ? null : `per-step sum ${perStep} ${t.step_unit}`,
    };
  }
  if (perStep === null) return null;
  return { label: capitalise(agent.measure), value: perStep, goal: null, detail: null };
}

/** The evaluation in one line, as the zip's README and `agent.evaluate` say it:
 * "backward turns per episode 0.23 ± 0.05 (threshold 1) · per-step sum 184 ± 2.62 rad/s",
 * or "true return 41.5 ± 3.2". */
export function scoreText(agent: Agent): string {
  const t = agent.target;
  const perStep =
    agent.true_return_mean === null ? null : meanSd(agent.true_return_mean, agent.true_return_std);
  if (!t) return perStep === null ? "not measured" : `${agent.measure} ${perStep}`;
  const parts = [];
  if (agent.target_score_mean !== null) {
    parts.push(
      `${t.unit} per episode ${meanSd(agent.target_score_mean, agent.target_score_std)} ` +
        `(threshold ${formatValue(t.threshold)})`,
    );
  }
  if (perStep !== null) parts.push(`per-step sum ${perStep} ${t.step_unit}`);
  return parts.join(" · ") || "not measured";
}

/** What the chart plots: a target env's episode score per round (with its threshold) when
 * the rounds recorded it, else the true return (`measure`). */
export interface ChartSeries {
  rounds: RoundResult[];
  /** What a value is, lower case: "backward turns per episode", "true return". */
  name: string;
  /** The target's threshold, drawn as a line; null for other envs. */
  reference: number | null;
}

export function chartSeries(agent: Agent): ChartSeries {
  const t = agent.target;
  if (t && agent.rounds.some((r) => r.target_score_mean !== null)) {
    return {
      rounds: agent.rounds.map((r) => ({ round: r.round, feedback: r.feedback, value: r.target_score_mean })),
      name: `${t.unit} per episode`,
      reference: t.threshold,
    };
  }
  return {
    rounds: agent.rounds.map((r) => ({
      round: r.round,
      feedback: r.feedback,
      value: r.true_return_mean,
    })),
    name: agent.measure,
    reference: null,
  };
}

/** Where every round's point goes in a `width` × `height` chart (rounds in index order);
 * the axis also covers `reference` when given. */
export function chartGeometry(
  rounds: readonly RoundResult[],
  width: number,
  height: number,
  margin: Margin = CHART_MARGIN,
  reference: number | null = null,
): ChartGeometry {
  const area = {
    left: margin.left,
    top: margin.top,
    right: Math.max(margin.left + 1, width - margin.right),
    bottom: Math.max(margin.top + 1, height - margin.bottom),
  };
  const sorted = [...rounds].sort((a, b) => a.round - b.round);
  const values = sorted.flatMap((r) => (r.value === null ? [] : [r.value]));
  const domain = values.length && reference !== null ? [...values, reference] : values;
  const ticks = domain.length ? niceTicks(Math.min(...domain), Math.max(...domain)) : [];
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
    y: r.value === null ? null : y(r.value),
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
    reference: reference === null || !ticks.length ? null : { value: reference, y: y(reference) },
  };
}
