import { describe, expect, it } from "vitest";
import { ApiError, type AgentOut, type Api, STALE, createApi } from "../src/api";
import { fakeApi } from "../bench/fake-api";
import { syntheticRound } from "../bench/synthetic";
import { createController } from "../src/controller";
import { choiceText, takeawayRounds } from "../src/lib/takeaway";
import { createStore } from "../src/state";

type Row = AgentOut["rounds"][number];

function row(round: number, patch: Partial<Row> = {}): Row {
  return {
    round,
    feedback: true,
    judgements: 3,
    pairs_total: 12,
    env_steps: 64 * (round + 1),
    true_return_mean: 10 * round,
    true_return_std: 1.5,
    target_score_mean: null,
    target_score_std: null,
    video: true,
    checkpoint: true,
    ...patch,
  };
}

const gridworld = {
  round: 2,
  chosen_by: "last" as const,
  measure: "true return",
  target: null,
  // the server's order is the rounds' order; the list does not rely on it
  rounds: [row(1, { judgements: 1 }), row(0), row(2, { feedback: false, judgements: 0 })],
};

describe("the rounds' agents to choose from", () => {
  it("lists every round in order with its score, the last one chosen until a pick", () => {
    const rounds = takeawayRounds(gridworld);
    expect(rounds.map((r) => r.round)).toEqual([0, 1, 2]);
    expect(rounds.map((r) => r.score)).toEqual(["True return 0.0 ± 1.5", "True return 10.0 ± 1.5", "True return 20.0 ± 1.5"]);
    expect(rounds.map((r) => r.kind)).toEqual(["after 3 comparisons", "after 1 comparison", "PPO on the frozen reward"]);
    expect(rounds.map((r) => r.chosen)).toEqual([false, false, true]);
    expect(rounds.map((r) => r.last)).toEqual([false, false, true]);
    expect(choiceText(gridworld)).toBe("Chosen: round 2 (last round)");
  });

  it("marks the person's pick, which need not be the last round", () => {
    const picked = { ...gridworld, round: 0, chosen_by: "person" as const };
    const rounds = takeawayRounds(picked);
    expect(rounds.map((r) => r.chosen)).toEqual([true, false, false]);
    expect(rounds[2]!.last).toBe(true);
    expect(choiceText(picked)).toBe("Chosen: round 0 (your pick)");
    expect(choiceText({ round: 1, chosen_by: "teacher" })).toBe("Chosen: round 1 (the simulated teacher's pick)");
  });

  it("says which rounds were not evaluated, not filmed, or cannot be taken", () => {
    const rounds = takeawayRounds({
      ...gridworld,
      rounds: [
        row(0, { true_return_mean: null, true_return_std: null }),
        row(1, { video: false }),
        row(2, { checkpoint: false }),
      ],
    });
    expect(rounds[0]!.score).toBeNull();
    expect(rounds.map((r) => r.clip)).toEqual([true, false, true]);
    expect(rounds.map((r) => r.blocked === null)).toEqual([true, true, false]);
    expect(rounds[2]!.blocked).toMatch(/checkpoint/);
  });

  it("gives a target env's rounds their episode score in the target's unit", () => {
    const target = { name: "backflip", unit: "backward turns", step_unit: "rad/s", threshold: 1, stretch: 2 };
    const rounds = takeawayRounds({
      ...gridworld,
      measure: "per-step score sum (rad/s)",
      target,
      rounds: [
        row(0, { target_score_mean: 0.23, target_score_std: 0.05, true_return_mean: 184 }),
        row(1, { target_score_mean: null, true_return_mean: 66.5, true_return_std: null }),
      ],
    });
    expect(rounds.map((r) => r.score)).toEqual(["Backward turns 0.230 ± 0.050", "Per-step sum 66.5 rad/s"]);
  });
});

describe("taking a round's agent", () => {
  const round = syntheticRound(20, { suggestions: 5, history: 0, seed: 1 });

  async function finished(pickAgent?: Api["pickAgent"]) {
    const api = fakeApi(round, "groupwise", { phase: "finished" }) as Api;
    const sent: number[] = [];
    const store = createStore();
    const controller = createController(
      store,
      {
        ...api,
        pickAgent: async (sid: string, r: number) => {
          sent.push(r);
          return (pickAgent ?? api.pickAgent)(sid, r);
        },
      } as Api,
      { storage: null },
    );
    await controller.boot("s-demo");
    await new Promise((r) => setTimeout(r, 0));
    return { store, controller, sent };
  }

  it("sends the round and makes the server's answer the page's agent", async () => {
    const { store, controller, sent } = await finished();
    expect(store.getState().agent?.data?.chosen_by).toBe("last");
    const agent = await controller.pickAgent(0);
    expect(sent).toEqual([0]);
    expect(agent.round).toBe(0);
    expect(store.getState().agent?.data).toMatchObject({ round: 0, chosen_by: "person" });
    expect(takeawayRounds(store.getState().agent!.data!).find((r) => r.chosen)?.round).toBe(0);
  });

  it("rejects with the server's reason and leaves the agent as it was", async () => {
    const reason = "round 0's checkpoint has no policy.zip: its policy cannot be packaged";
    const { store, controller } = await finished(async () => {
      throw new ApiError(409, reason);
    });
    const before = store.getState().agent;
    await expect(controller.pickAgent(0)).rejects.toThrow(reason);
    expect(store.getState().agent).toBe(before);
  });
});

describe("the pick on the wire", () => {
  function fetchOnce(status: number, body: unknown) {
    const calls: Array<{ url: string; init: RequestInit }> = [];
    const pending: Array<() => void> = [];
    const fetch = ((url: string, init: RequestInit) => {
      calls.push({ url, init });
      const answer = calls.length === 1 && init.method === "GET" ? { round: 2 } : body;
      const code = calls.length === 1 && init.method === "GET" ? 200 : status;
      return new Promise<Response>((resolve) =>
        pending.push(() => resolve(new Response(JSON.stringify(answer), { status: code }))),
      );
    }) as unknown as typeof globalThis.fetch;
    /** Answers the requests, the last sent first. */
    const release = () => pending.splice(0).reverse().forEach((go) => go());
    return { fetch, calls, release };
  }

  it("PUTs the round, and an agent read it overtook is dropped", async () => {
    const { fetch, calls, release } = fetchOnce(200, { round: 0, chosen_by: "person" });
    const api = createApi({ fetch, base: "http://x/" });
    const read = api.agent("s-1");
    const picked = api.pickAgent("s-1", 0);
    release();
    expect(await picked).toEqual({ round: 0, chosen_by: "person" });
    expect(await read).toBe(STALE);
    expect(calls[1]!.url).toBe("http://x/api/sessions/s-1/agent/round");
    expect(calls[1]!.init.method).toBe("PUT");
    expect(JSON.parse(String(calls[1]!.init.body))).toEqual({ round: 0 });
    expect(api.agentRoundVideoUrl("s-1", 3)).toBe("http://x/api/sessions/s-1/agent/rounds/3.mp4");
  });

  it("rejects with the server's reason", async () => {
    const reason = "round 0's checkpoint has no policy.zip: its policy cannot be packaged";
    const { fetch, release } = fetchOnce(409, { detail: reason });
    const api = createApi({ fetch, base: "http://x/" });
    const picked = api.pickAgent("s-1", 0);
    release();
    await expect(picked).rejects.toMatchObject({ status: 409, message: reason });
  });
});
