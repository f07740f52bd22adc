import { describe, expect, it } from "vitest";
import { ApiError, type Api } from "../src/api";
import { fakeApi } from "../src/bench/fake-api";
import { syntheticRound } from "../src/bench/synthetic";
import { createController } from "../src/controller";
import { chartGeometry, formatValue, niceTicks } from "../src/lib/results";
import { createStore } from "../src/state";
import { canFinish, roundText } from "../src/views/status";

const rounds = [
  { round: 0, feedback: true, true_return_mean: -10, true_return_std: 1 },
  { round: 1, feedback: true, true_return_mean: 5, true_return_std: 1 },
  { round: 2, feedback: false, true_return_mean: 20, true_return_std: 1 },
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
      [...rounds.slice(0, 2), { round: 2, feedback: false, true_return_mean: null, true_return_std: null }],
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
