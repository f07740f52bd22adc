import { describe, expect, it } from "vitest";
import { ApiError, type Api } from "../src/api";
import { fakeApi } from "../bench/fake-api";
import { syntheticRound } from "../bench/synthetic";
import { createController } from "../src/controller";
import { chartGeometry, chartSeries, formatValue, meanSd, niceTicks, scoreLines, scoreText } from "../src/lib/results";
import { createStore } from "../src/state";
import { canFinish, roundText } from "../src/views/status";

const rounds = [
  { round: 0, feedback: true, value: -10 },
  { round: 1, feedback: true, value: 5 },
  { round: 2, feedback: false, value: 20 },
];

describe("the finished page's chart", () => {
  it("picks round ticks that cover the values", () => {
    expect(niceTicks(-10, 20)).toEqual([-10, 0, 10, 20]);
    expect(niceTicks(0.12, 0.5)).toEqual([0.1, 0.2, 0.3, 0.4, 0.5]);
    expect(niceTicks(3, 3).length).toBeGreaterThan(1); // one value still gets an axis
  });

  it("places rounds left to right and higher returns higher", () => {
    const g = chartGeometry(rounds, 200, 100, { top: 0, right: 0, bottom: 0, left: 0 });
    expect(g.points.map((p) => p.x)).toEqual([0, 100, 200]);
    expect(g.points.map((p) => p.y)).toEqual([100, 50, 0]);
    expect(g.path).toBe("M0,100L100,50L200,0");
    expect(g.points[2]!.feedback).toBe(false);
  });

  it("leaves unevaluated rounds out of the line", () => {
    const g = chartGeometry(
      [...rounds.slice(0, 2), { round: 2, feedback: false, value: null }],
      200,
      100,
      { top: 0, right: 0, bottom: 0, left: 0 },
    );
    expect(g.points[2]!.y).toBeNull();
    expect(g.path.split("L")).toHaveLength(2);
  });

  it("formats values briefly", () => {
    expect(formatValue(1234.56)).toBe("1,235");
    expect(formatValue(0.123456)).toBe("0.123");
    expect(formatValue(-12.34)).toBe("-12.3");
    expect(formatValue(0.000912)).toBe("0.000912"); // a small score keeps its digits
    expect(formatValue(999.6)).toBe("1,000");
  });

  it("writes mean ± sd to one decimal place, no finer than the mean's third figure", () => {
    expect(meanSd(0.14, 0.000621)).toBe("0.140 ± 0.001"); // issue 40: "0.14 ± 0.000621"
    expect(meanSd(0.14, 0.00004)).toBe("0.140 ± 0.001"); // never "± 0.000"
    expect(meanSd(184.3, 2.62)).toBe("184 ± 3");
    expect(meanSd(41.5, 3.2)).toBe("41.5 ± 3.2");
    expect(meanSd(-127.4, 12.3)).toBe("-127 ± 12");
    expect(meanSd(0.00912, 0.0004)).toBe("0.00912 ± 0.00040");
    expect(meanSd(5.123, 300)).toBe("5 ± 300");
    expect(meanSd(1234.56, 12.3)).toBe("1,235 ± 12");
    expect(meanSd(0, 0.5)).toBe("0.00 ± 0.50");
    expect(meanSd(3.5, 0)).toBe("3.5 ± 0");
    expect(meanSd(3.5, null)).toBe("3.5");
  });

  it("covers a reference value and says where it lies", () => {
    const small = rounds.slice(0, 2).map((r) => ({ ...r, value: r.value / 100 }));
    const g = chartGeometry(small, 200, 100, { top: 0, right: 0, bottom: 0, left: 0 }, 1);
    expect(g.yTicks[g.yTicks.length - 1]!.value).toBe(1); // the axis reaches the threshold
    expect(g.reference).toEqual({ value: 1, y: 0 });
    expect(chartGeometry(rounds, 200, 100).reference).toBeNull();
  });
});

// issue 23: a Hopper-backflip agent's episode score was 0.23 turns, its per-step sum 184
function row(round: number, feedback: boolean, perStepSum: number, score: number) {
  return { round, feedback, judgements: 0, pairs_total: 9, env_steps: 64 * (round + 1),
    true_return_mean: perStepSum, target_score_mean: score, checkpoint: true, video: false };
}
const backflip = {
  measure: "per-step score sum (rad/s)",
  true_return_mean: 184.3,
  true_return_std: 2.62,
  target: { name: "hopper-backflip", unit: "backward turns", step_unit: "rad/s", threshold: 1, stretch: 2 },
  target_score_mean: 0.2312,
  target_score_std: 0.05,
  rounds: [
    { ...row(0, true, 150, 0.19), true_return_std: 1, target_score_std: 0.01 },
    { ...row(1, false, 184.3, 0.2312), true_return_std: 2.62, target_score_std: 0.05 },
  ],
};

describe("the finished page's evaluation", () => {
  it("leads with a target's episode score in its unit, the per-step sum beside it", () => {
    expect(scoreText(backflip)).toBe(
      "backward turns per episode 0.231 ± 0.050 (threshold 1) · per-step sum 184 ± 3 rad/s",
    );
    expect(scoreLines(backflip)).toEqual({
      label: "Backward turns per episode",
      value: "0.231 ± 0.050",
      goal: "threshold 1 · stretch 2",
      detail: "per-step sum 184 ± 3 rad/s",
    });
    const series = chartSeries(backflip);
    expect(series.rounds.map((r) => r.value)).toEqual([0.19, 0.2312]);
    expect(series.reference).toBe(1);
    expect(series.name).toBe("backward turns per episode");
  });

  it("names the true return of other envs, and an old agent's per-step sum as what it is", () => {
    const plain = {
      ...backflip,
      measure: "true return",
      target: null,
      target_score_mean: null,
      target_score_std: null,
    };
    expect(scoreText(plain)).toBe("true return 184 ± 3");
    expect(scoreLines(plain)).toEqual({ label: "True return", value: "184 ± 3", goal: null, detail: null });
    expect(chartSeries(plain).rounds.map((r) => r.value)).toEqual([150, 184.3]);
    // published before episode scores were recorded: the target is known, its score is not
    const old = {
      ...backflip,
      target_score_mean: null,
      target_score_std: null,
      rounds: backflip.rounds.map((r) => ({ ...r, target_score_mean: null, target_score_std: null })),
    };
    expect(scoreText(old)).toBe("per-step sum 184 ± 3 rad/s");
    expect(chartSeries(old)).toMatchObject({ name: "per-step score sum (rad/s)", reference: null });
    expect(scoreLines({ ...plain, true_return_mean: null })).toBeNull();
  });
});

describe("the end of a session", () => {
  const round = syntheticRound(20, { suggestions: 5, history: 0, seed: 1 });

  it("names the final phase's rounds and offers Finish now only while it can", () => {
    expect(roundText({ round: 2, rounds: 5 })).toBe("Round 2 of 0–4");
    expect(roundText({ round: 5, rounds: 5 })).toBe("Round 5 · final phase");
    const base = { settings: { driver: "app" }, round: 0 } as Parameters<typeof canFinish>[0];
    expect(canFinish({ ...base, phase: "ready" })).toBe(true);
    expect(canFinish({ ...base, phase: "preparing" })).toBe(false); // nothing learned yet
    expect(canFinish({ ...base, phase: "preparing", round: 1 })).toBe(true);
    expect(canFinish({ ...base, phase: "finished" })).toBe(false);
  });

  it("loads the finished session's agent once, and knows a session without one", async () => {
    const api = fakeApi(round, "groupwise", { phase: "finished" }) as Api;
    let calls = 0;
    const store = createStore();
    const controller = createController(store, {
      ...api,
      agent: async (sid: string) => {
        calls++;
        return api.agent(sid);
      },
    } as Api, { storage: null });
    await controller.boot("s-demo");
    await new Promise((r) => setTimeout(r, 0));
    expect(store.getState().agent?.data?.rounds).toHaveLength(6);
    expect(calls).toBe(1);

    const none = createStore();
    const missing = createController(none, {
      ...api,
      agent: async () => {
        throw new ApiError(404, "no agent");
      },
    } as Api, { storage: null });
    await missing.boot("s-demo");
    await new Promise((r) => setTimeout(r, 0));
    expect(none.getState().agent).toEqual({ key: "s-demo:1", data: null });
    expect(none.getState().toast).toBeNull();
  });

  it("sends Continue training's choice as its body", async () => {
    const api = fakeApi(round, "groupwise", { phase: "finished" }) as Api;
    const sent: unknown[] = [];
    const store = createStore();
    const controller = createController(store, {
      ...api,
      continueTraining: async (sid: string, body: Parameters<Api["continueTraining"]>[1]) => {
        sent.push(body);
        return api.continueTraining(sid, body);
      },
    } as Api, { storage: null });
    await controller.boot("s-demo");
    await controller.continueTraining({ steps: 5000 });
    expect(sent).toEqual([{ steps: 5000 }]);
    expect(store.getState().session?.phase).toBe("finishing");
  });
});
