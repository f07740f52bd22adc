import { describe, expect, it, vi } from "vitest";
import { type Api, ApiError, type Settings } from "../src/api";
import { fakeApi } from "../bench/fake-api";
import { syntheticRound } from "../bench/synthetic";
import { createController } from "../src/controller";
import { createStore } from "../src/state";

const round = syntheticRound(40, { suggestions: 20, history: 0, seed: 5 });

function setup(mode: "groupwise" | "pairwise", patch: Partial<Api> = {}) {
  const api = { ...fakeApi(round, mode), ...patch } as Api;
  const store = createStore();
  const controller = createController(store, api, { storage: null });
  return { api, store, controller };
}

function deferred<T>() {
  let resolve!: (v: T) => void;
  const promise = new Promise<T>((r) => (resolve = r));
  return { promise, resolve };
}

describe("controller (groupwise)", () => {
  it("pre-fills a suggestion when both groups are empty", async () => {
    const { store, controller } = setup("groupwise");
    await controller.boot("s-demo");
    const st = store.getState();
    expect(st.round?.tree.leaves).toHaveLength(40);
    expect(st.groups.A.length).toBeGreaterThan(0);
    expect(st.origin.source).toBe("suggested");
  });

  it("never overwrites groups chosen while the suggestion was on its way", async () => {
    const gate = deferred<void>();
    const base = fakeApi(round, "groupwise");
    const { store, controller } = setup("groupwise", {
      nextSuggestion: async (...args) => {
        await gate.promise;
        return base.nextSuggestion(...args);
      },
    });
    const booted = controller.boot("s-demo");
    await vi.waitFor(() => expect(store.getState().suggestionStatus).toBe("loading"));
    store.dispatch({ type: "select", click: { leaves: ["b1"], isLeaf: true, add: false }, other: false, at: 1 });
    gate.resolve();
    await booted;
    expect(store.getState().groups).toEqual({ A: ["b1"], B: [] });
  });

  it("sends one judgement per answer, with source, edits and time", async () => {
    const { api, store, controller } = setup("groupwise");
    const submit = vi.spyOn(api, "submitJudgement");
    await controller.boot("s-demo");
    store.dispatch({ type: "clear" });
    store.dispatch({ type: "select", click: { leaves: ["b1", "b2"], isLeaf: false, add: false }, other: false, at: Date.now() });
    store.dispatch({ type: "select", click: { leaves: ["b3"], isLeaf: true, add: false }, other: true, at: Date.now() });
    await Promise.all([controller.answer("right"), controller.answer("right"), controller.answer("left")]);
    expect(submit).toHaveBeenCalledTimes(1);
    const body = submit.mock.calls[0]![1];
    expect(body).toMatchObject({ left: ["b1", "b2"], right: ["b3"], label: "right", source: "explored", edits: 2, round: 1 });
    expect(body.client_id).toMatch(/^[0-9a-f-]{36}$/);
    const st = store.getState();
    expect(st.judgements.at(-1)?.label).toBe("right");
    expect(st.toast?.text).toBe("Saved: right better · 2 preference pairs.");
  });

  it("an answer key with a group empty saves nothing and says why", async () => {
    const { api, store, controller } = setup("groupwise");
    const submit = vi.spyOn(api, "submitJudgement");
    await controller.boot("s-demo");
    store.dispatch({ type: "clear" });
    store.dispatch({ type: "select", click: { leaves: ["b1"], isLeaf: true, add: false }, other: false, at: Date.now() });
    await controller.answer("left");
    expect(submit).not.toHaveBeenCalled();
    expect(store.getState().toast?.text).toMatch(/No answer saved: group B is empty/);
  });

  it("undo deletes the last judgement and brings its groups back", async () => {
    const { api, store, controller } = setup("groupwise");
    const undo = vi.spyOn(api, "undoJudgement");
    await controller.boot("s-demo");
    store.dispatch({ type: "set-groups", groups: { A: ["b4"], B: ["b5", "b6"] }, origin: { source: "suggested", edits: 0, startedAt: 0, suggestion: null } });
    await controller.answer("equal");
    const id = store.getState().judgements.at(-1)!.id;
    await controller.undo();
    expect(undo).toHaveBeenCalledWith("s-demo", id);
    expect(store.getState().judgements.some((j) => j.id === id)).toBe(false);
    expect(store.getState().groups).toEqual({ A: ["b4"], B: ["b5", "b6"] });
    expect(store.getState().origin.source).toBe("suggested");
  });
});

describe("controller (pairwise)", () => {
  it("shows the following pair at once and sends the answer behind it", async () => {
    const gate = deferred<void>();
    const base = fakeApi(round, "pairwise");
    const { store, controller } = setup("pairwise", {
      submitJudgement: async (...args) => {
        await gate.promise;
        return base.submitJudgement(...args);
      },
    });
    await controller.boot("s-demo");
    const first = store.getState().pairwise.current!;
    const following = store.getState().pairwise.following!;
    controller.answerPair("left");
    // on screen before the server has even answered
    expect(store.getState().pairwise.current).toEqual(following);
    gate.resolve();
    await vi.waitFor(() => expect(store.getState().judgements.at(-1)?.left).toEqual([first.left]));
    expect(store.getState().pairwise.done).toContain(`${first.left}:${first.right}`);
  });
});

describe("controller (round timer)", () => {
  it("reports the round shown once its data is on screen, and only once", async () => {
    const { api, store, controller } = setup("groupwise");
    const shown = vi.spyOn(api, "shown");
    await controller.boot("s-demo");
    await vi.waitFor(() => expect(shown).toHaveBeenCalledTimes(1));
    expect(shown).toHaveBeenCalledWith("s-demo", 1);
    expect(store.getState().session?.timer.shown_at).toBeTruthy();
    await controller.reportShown();
    expect(shown).toHaveBeenCalledTimes(1);
  });

  it("waits while the guide covers the page or the page is hidden", async () => {
    const api = fakeApi(round, "pairwise");
    const shown = vi.spyOn(api, "shown");
    const store = createStore();
    let visible = false;
    const controller = createController(store, api, { storage: null, visible: () => visible });
    let offered = false; // as the page does: the guide opens as the session does
    store.subscribe((st) => {
      if (st.boot !== "ready" || offered) return;
      offered = true;
      store.dispatch({ type: "guide", open: true });
    });
    await controller.boot("s-demo");
    expect(shown).not.toHaveBeenCalled();
    visible = true;
    await controller.reportShown();
    expect(shown).not.toHaveBeenCalled(); // the guide is open
    store.dispatch({ type: "guide", open: false });
    await controller.reportShown();
    expect(shown).toHaveBeenCalledWith("s-demo", 1);
  });
});

describe("controller (new session)", () => {
  const refuse = (message: string) => Promise.reject(new ApiError(422, message));

  it("shows what the server would store, and the env's refusal beside the env", async () => {
    const { store, controller } = setup("groupwise", {
      resolveSettings: async (body) => {
        if (body.env === "Bogus-v9") return refuse("unknown env 'Bogus-v9'");
        return { ...(await fakeApi(round, "groupwise").resolveSettings(body)) as Settings, pool_size: 42 };
      },
    });
    await controller.checkNewSession({ env: "Hopper", mode: "groupwise" });
    expect(store.getState().newSession).toMatchObject({ envError: null, error: null });
    expect(store.getState().newSession.resolved?.pool_size).toBe(42);
    await controller.checkNewSession({ env: "Bogus-v9", mode: "groupwise", settings: { rounds: 3 } });
    expect(store.getState().newSession).toMatchObject({ envError: "unknown env 'Bogus-v9'", error: null });
  });

  it("puts a refusal of the settings above the form, and creates nothing", async () => {
    const createSession = vi.fn();
    const { store, controller } = setup("groupwise", {
      createSession,
      resolveSettings: async (body) =>
        body.settings?.clip_seconds ? refuse("env Hopper needs a fixed horizon") : fakeApi(round, "groupwise").resolveSettings(body),
    });
    await controller.checkNewSession({ env: "Hopper", mode: "groupwise", settings: { clip_seconds: 20 } });
    expect(store.getState().newSession).toMatchObject({ envError: null, error: "env Hopper needs a fixed horizon" });
    createSession.mockImplementation(() => refuse("env Hopper needs a fixed horizon"));
    await controller.create({ env: "Hopper", mode: "groupwise", settings: { clip_seconds: 20 } });
    expect(store.getState().newSession.error).toBe("env Hopper needs a fixed horizon");
    expect(store.getState().boot).not.toBe("ready");
  });
});
