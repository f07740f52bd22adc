import { describe, expect, it } from "vitest";
import { ApiError, STALE, createApi, errorMessage } from "../src/api";
import type { JudgementIn } from "../src/api";

interface Call {
  url: string;
  init: RequestInit;
  resolve(status: number, body: unknown): void;
  reject(err: Error): void;
}

/** A fetch whose responses the test releases one by one, in any order. */
function fakeFetch() {
  const calls: Call[] = [];
  const fetch = ((url: string, init: RequestInit) =>
    new Promise<Response>((res, rej) => {
      calls.push({
        url,
        init,
        resolve: (status, body) =>
          res(new Response(body === undefined ? "" : JSON.stringify(body), { status })),
        reject: rej,
      });
    })) as unknown as typeof globalThis.fetch;
  return { fetch, calls };
}

const tick = () => new Promise((r) => setTimeout(r, 0));

describe("stale responses", () => {
  it("drops a response that arrives after a newer request of the same resource", async () => {
    const { fetch, calls } = fakeFetch();
    const api = createApi({ fetch, base: "http://x/" });
    const first = api.tree("s-1", 0);
    const second = api.tree("s-1", 1);
    calls[1]!.resolve(200, { round: 1 });
    calls[0]!.resolve(200, { round: 0 });
    expect(await second).toEqual({ round: 1 });
    expect(await first).toBe(STALE);
  });

  it("keeps resources apart", async () => {
    const { fetch, calls } = fakeFetch();
    const api = createApi({ fetch, base: "http://x/" });
    const tree = api.tree("s-1", 0);
    const edges = api.edges("s-1", 0, 5);
    calls[1]!.resolve(200, []);
    calls[0]!.resolve(200, { round: 0 });
    expect(await tree).toEqual({ round: 0 });
    expect(await edges).toEqual([]);
    expect(calls[1]!.url).toBe("http://x/api/sessions/s-1/rounds/0/edges?k=5");
  });

  it("drops a session read overtaken by a control reply", async () => {
    const { fetch, calls } = fakeFetch();
    const api = createApi({ fetch, base: "http://x/" });
    const read = api.session("s-1");
    const pause = api.control("s-1", "pause");
    calls[1]!.resolve(200, { id: "s-1", timer: { paused: true } });
    await pause;
    calls[0]!.resolve(200, { id: "s-1", timer: { paused: false } });
    expect(await read).toBe(STALE);
  });

  it("turns a stale failure into STALE too (no message for an outdated request)", async () => {
    const { fetch, calls } = fakeFetch();
    const api = createApi({ fetch, base: "http://x/" });
    const first = api.judgements("s-1", 0);
    api.invalidate("judgements");
    calls[0]!.resolve(409, { detail: "round 0 is closed" });
    expect(await first).toBe(STALE);
  });
});

describe("errors", () => {
  it("uses the server's detail", async () => {
    const { fetch, calls } = fakeFetch();
    const api = createApi({ fetch, base: "http://x/" });
    const p = api.envs();
    calls[0]!.resolve(409, { detail: "round 1 is closed; the open round is 2" });
    await expect(p).rejects.toThrow("round 1 is closed; the open round is 2");
    await expect(p).rejects.toBeInstanceOf(ApiError);
  });

  it("flattens FastAPI's validation list and has sentences for bare statuses", () => {
    expect(
      errorMessage(422, {
        detail: [
          { loc: ["body", "settings", "pool_size"], msg: "Input should be greater than or equal to 8" },
          { loc: ["body", "env"], msg: "Field required" },
        ],
      }),
    ).toBe("settings.pool_size: Input should be greater than or equal to 8; env: Field required");
    expect(errorMessage(500, "<html>")).toMatch(/server failed \(500\)/);
    expect(errorMessage(413, null)).toMatch(/too large/);
  });

  it("says so when the server cannot be reached", async () => {
    const fetch = (() => Promise.reject(new TypeError("Failed to fetch"))) as unknown as typeof globalThis.fetch;
    const api = createApi({ fetch, base: "http://x/" });
    await expect(api.sessions()).rejects.toMatchObject({ network: true, message: expect.stringMatching(/Cannot reach/) });
  });
});

describe("judgements", () => {
  const body: JudgementIn = {
    client_id: "id-1",
    round: 0,
    left: ["b1"],
    right: ["b2"],
    label: "left",
    source: "explored",
    seconds: 1,
    edits: 0,
    annotator: "",
  };

  it("retries a network failure with the same client_id", async () => {
    const { fetch, calls } = fakeFetch();
    const api = createApi({ fetch, base: "http://x/", retryDelays: [0, 0], sleep: async () => undefined });
    const p = api.submitJudgement("s-1", body);
    await tick();
    calls[0]!.reject(new TypeError("network"));
    await tick();
    await tick();
    calls[1]!.resolve(200, { ...body, id: 3, pairs: [] });
    expect(await p).toMatchObject({ id: 3 });
    expect(calls).toHaveLength(2);
    expect(calls.map((c) => JSON.parse(String(c.init.body)).client_id)).toEqual(["id-1", "id-1"]);
    expect(calls[0]!.init.method).toBe("POST");
  });

  it("does not retry a refusal", async () => {
    const { fetch, calls } = fakeFetch();
    const api = createApi({ fetch, base: "http://x/", retryDelays: [0], sleep: async () => undefined });
    const p = api.submitJudgement("s-1", body);
    await tick();
    calls[0]!.resolve(422, { detail: "b1 is in both groups" });
    await expect(p).rejects.toThrow("b1 is in both groups");
    expect(calls).toHaveLength(1);
  });
});

describe("urls and token", () => {
  it("sends the token as a header and on clip and event URLs", async () => {
    const { fetch, calls } = fakeFetch();
    const api = createApi({ fetch, base: "http://x/app/", token: "t0k" });
    void api.envs();
    expect((calls[0]!.init.headers as Record<string, string>).Authorization).toBe("Bearer t0k");
    expect(calls[0]!.url).toBe("http://x/app/api/envs");
    expect(api.clipUrl("ab.mp4")).toBe("http://x/app/clips/ab.mp4?token=t0k");
  });

  it("sends excluded suggestions as consecutive left/right lists", async () => {
    const { fetch, calls } = fakeFetch();
    const api = createApi({ fetch, base: "http://x/" });
    void api.nextSuggestion("s-1", 2, [[["b1"], ["b2", "b3"]], [["b4"], ["b5"]]]);
    expect(JSON.parse(String(calls[0]!.init.body))).toEqual({ exclude: [["b1"], ["b2", "b3"], ["b4"], ["b5"]] });
    void api.nextSuggestion("s-1", 2);
    expect(JSON.parse(String(calls[1]!.init.body))).toEqual({});
  });
});
