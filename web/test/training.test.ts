import { describe, expect, it } from "vitest";
import type { TrainingPoint } from "../src/api";
import { createStore } from "../src/state";
import {
  axisTitles,
  clockLabel,
  curveGeometry,
  mergePoints,
  summaryLines,
  timeTicks,
  trainingSummary,
} from "../src/lib/training";

const T0 = Date.parse("2030-01-01T12:00:00Z");

function point(seconds: number, ppo: number, value: number | null, extra: Partial<TrainingPoint> = {}): TrainingPoint {
  return {
    round: 0,
    at: new Date(T0 + seconds * 1000).toISOString(),
    ppo_steps: ppo,
    true_return: value,
    pairs: 4,
    reward_val_accuracy: 0.75,
    pool_steps: 0,
    ...extra,
  };
}

const NONE = { top: 0, right: 0, bottom: 0, left: 0 };

describe("the learning curve's geometry", () => {
  it("places time left to right and higher returns higher, refits left out", () => {
    const points = [point(0, 0, -10), point(5, 0, null), point(10, 64, 0), point(20, 128, 10)];
    const g = curveGeometry(points, 200, 100, NONE);
    expect(g.points.map((p) => [p.seconds, p.x, p.y])).toEqual([
      [0, 0, 100],
      [10, 100, 50],
      [20, 200, 0],
    ]);
    expect(g.path).toBe("M0,100L100,50L200,0");
    expect(g.yTicks.map((t) => t.value)).toEqual([-10, 0, 10]);
    expect(g.xTicks.map((t) => t.label)).toEqual(["0:00", "0:05", "0:10", "0:15", "0:20"]);
  });

  it("counts time from the session's first point, evaluated or not", () => {
    const g = curveGeometry([point(0, 0, null), point(30, 64, 2), point(60, 128, 4)], 100, 100, NONE);
    expect(g.points.map((p) => p.seconds)).toEqual([30, 60]);
    expect(g.points.map((p) => p.x)).toEqual([50, 100]);
  });

  it("centres a single point and draws nothing without one", () => {
    const one = curveGeometry([point(0, 0, 3)], 100, 50, NONE);
    expect(one.points[0]!.x).toBe(50);
    expect(one.xTicks.map((t) => t.label)).toEqual(["0:00"]);
    const none = curveGeometry([point(0, 0, null)], 100, 50, NONE);
    expect([none.points, none.path, none.yTicks, none.xTicks]).toEqual([[], "", [], []]);
  });

  it("labels a curve of under a few seconds once per whole second (not 0:00 0:00 0:00 0:00)", () => {
    expect(timeTicks(0)).toEqual([0]);
    expect(timeTicks(0.4)).toEqual([0]);
    expect(timeTicks(2.5)).toEqual([0, 1, 2]);
    const labels = curveGeometry([point(0, 0, 1), point(0.6, 64, 2)], 100, 50, NONE).xTicks;
    expect(labels.map((t) => t.label)).toEqual(["0:00"]);
  });

  it("titles its axes with their units: the true return, or a target's per-step score", () => {
    expect(curveGeometry([point(0, 0, 3)], 100, 50).titles).toEqual({ x: "session time (m:ss)", y: "true return" });
    expect(axisTitles({ unit: "s", step_unit: "rad/s" }).y).toBe("per-step score sum (rad/s)");
    expect(axisTitles({ unit: "s" }).y).toBe("per-step score sum");
  });

  it("writes session time as m:ss or h:mm:ss", () => {
    expect([clockLabel(0), clockLabel(75), clockLabel(3725)]).toEqual(["0:00", "1:15", "1:02:05"]);
  });
});

describe("the learning in words", () => {
  it("summarises the newest point with the newest evaluated return", () => {
    const points = [point(0, 0, -3), point(10, 12_288, null, { pairs: 14, reward_val_accuracy: 0.784, pool_steps: 2048 })];
    const summary = trainingSummary(points)!;
    expect(summary).toEqual({
      round: 0,
      ppoSteps: 12_288,
      pairs: 14,
      valAccuracy: 0.784,
      poolAge: 10_240,
      trueReturn: -3,
    });
    expect(summaryLines(summary)).toEqual({
      steps: "12,288 PPO steps",
      refit: "Last refit: 14 pairs · 78 % of held-out pairs right",
      pool: "Pool sampled 10,240 PPO steps ago",
    });
    expect(summaryLines({ ...summary, pairs: 1, valAccuracy: null, poolAge: 1 })).toMatchObject({
      refit: "Last refit: 1 pair",
      pool: "Pool sampled 1 PPO step ago",
    });
    expect(trainingSummary([])).toBeNull();
  });

  it("tells the shown round's pool age, though the ended round's record comes after it", () => {
    const points = [
      point(0, 4096, null, { round: 1, pool_steps: 2048 }),
      point(1, 6144, null, { round: 2, pool_steps: 6000 }), // round 2 opened
      point(2, 6144, 5, { round: 1, pool_steps: 2048 }), // round 1 committed after
    ];
    const summary = trainingSummary(points)!;
    expect([summary.round, summary.ppoSteps, summary.poolAge, summary.trueReturn]).toEqual([2, 6144, 144, 5]);
  });
});

describe("the store's curve", () => {
  it("merges the read and the events once each, in time order, per session", () => {
    const a = point(0, 0, 1);
    const b = point(10, 64, 2);
    expect(mergePoints([b], [a, b])).toEqual([a, b]);
    const store = createStore();
    store.dispatch({ type: "training", sid: "s-1", points: [b] });
    store.dispatch({ type: "training", sid: "s-1", points: [a, b] });
    expect(store.getState().training).toEqual({ sid: "s-1", points: [a, b] });
    store.dispatch({ type: "training", sid: "s-2", points: [a] });
    expect(store.getState().training).toEqual({ sid: "s-2", points: [a] });
  });
});
