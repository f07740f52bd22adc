/** The page in a shared session (issue 21): others' answers, undo refused, the counters. */
import { describe, expect, it, vi } from "vitest";
import { type Annotator, type Api, ApiError, type EventHandlers, type JudgementOut, type Me } from "../src/api";
import { fakeApi } from "../bench/fake-api";
import { syntheticRound } from "../bench/synthetic";
import { createController } from "../src/controller";
import { createStore } from "../src/state";

const round = syntheticRound(40, { suggestions: 20, history: 0, seed: 5 });
const OWNER: Me = { id: "owner", name: "owner", owner: true };
const ANN: Me = { id: "a-1", name: "Ann", owner: false };

function person(id: string, name: string, comparisons = 0, pairs = 0): Annotator {
  return {
    id,
    name,
    comparisons,
    pairs,
    shown_s: 0,
    agreement: { kappa: null, share: null, n: 0 },
    model_agreement: { share: null, n: 0 },
  };
}

function setup(mode: "groupwise" | "pairwise", me: Me, patch: Partial<Api> = {}) {
  const annotators = [person("owner", "owner", 3, 6), person("a-1", "Ann", 1, 2)];
  const base = fakeApi(round, mode, { me, annotators });
  const stream: { handlers: EventHandlers | null } = { handlers: null };
  const api = {
    ...base,
    events: (_sid: string, handlers: EventHandlers) => {
      stream.handlers = handlers;
      setTimeout(() => handlers.open?.(), 0);
      return () => undefined;
    },
    ...patch,
  } as Api;
  const store = createStore();
  const controller = createController(store, api, { storage: null });
  return { api, store, controller, stream, base };
}

/** Someone's judgement as the event stream sends it. */
function theirs(who: { id: string; name: string }, patch: Partial<JudgementOut>): JudgementOut {
  return {
    id: 900,
    client_id: "elsewhere",
    round: 1,
    left: ["b1"],
    right: ["b2"],
    label: "left",
    source: "suggested",
    seconds: 3,
    edits: 0,
    annotator: { id: who.id, name: who.name },
    suggestion_id: null,
    created_at: "2030-01-01T00:00:00Z",
    undone: false,
    pairs: [{ a: "b1", b: "b2", label: 1 }],
    ...patch,
  };
}

describe("someone else's answer", () => {
  it("takes the suggestion they answered off this page and shows the next one", async () => {
    const { store, controller, stream } = setup("groupwise", OWNER);
    await controller.boot("s-demo");
    const shown = store.getState().origin.suggestion!;
    expect(shown).not.toBeNull();
    stream.handlers!.judgement!(theirs(ANN, { left: shown.left, right: shown.right, suggestion_id: shown.id }), 20);
    await vi.waitFor(() => expect(store.getState().origin.suggestion?.id).not.toBe(shown.id));
    expect(store.getState().groups.A).not.toEqual(shown.left);
    expect(store.getState().toast?.text).toBe("Ann answered the suggestion you had; here is the next one.");
    expect(store.getState().judgements.some((j) => j.id === 900)).toBe(true); // in the history
  });

  it("leaves groups the person already edited, and says so", async () => {
    const { store, controller, stream } = setup("groupwise", OWNER);
    await controller.boot("s-demo");
    const shown = store.getState().origin.suggestion!;
    store.dispatch({ type: "remove", id: shown.left[0]!, at: Date.now() });
    const groups = store.getState().groups;
    stream.handlers!.judgement!(theirs(ANN, { left: shown.left, right: shown.right, suggestion_id: shown.id }), 20);
    await vi.waitFor(() => expect(store.getState().toast?.text).toMatch(/^Ann already answered the suggestion you are editing/));
    expect(store.getState().groups).toBe(groups);
  });

  it("ignores this page's own answers coming back through the stream", async () => {
    const { store, controller, stream } = setup("groupwise", ANN);
    await controller.boot("s-demo");
    const shown = store.getState().origin.suggestion!;
    stream.handlers!.judgement!(theirs(ANN, { left: shown.left, right: shown.right, suggestion_id: shown.id }), 20);
    await new Promise((r) => setTimeout(r, 0));
    expect(store.getState().origin.suggestion).toBe(shown);
  });

  it("in pairwise mode, moves on from the pair they answered", async () => {
    const { store, controller, stream } = setup("pairwise", ANN);
    await controller.boot("s-demo");
    const { current, following } = store.getState().pairwise;
    stream.handlers!.judgement!(theirs(OWNER, { left: [current!.right], right: [current!.left], source: "pairwise" }), 20);
    await vi.waitFor(() => expect(store.getState().pairwise.current).toEqual(following));
    expect(store.getState().toast?.text).toBe("owner answered the pair you had; here is the next one.");
  });
});

describe("becoming shared", () => {
  function alone() {
    const api = fakeApi(round, "groupwise", { me: OWNER, annotators: [person("owner", "owner")] });
    const store = createStore();
    const controller = createController(store, api, { storage: null });
    return { api, store, controller };
  }
  const shared = (store: ReturnType<typeof createStore>) =>
    store.dispatch({
      type: "session",
      session: { ...store.getState().session!, annotators: [person("owner", "owner"), person("a-1", "Ann")] },
      at: Date.now(),
    });

  it("asks for the suggestion on screen again, so that the server leases it to this page", async () => {
    const { api, store, controller } = alone();
    await controller.boot("s-demo");
    const shown = store.getState().origin.suggestion!;
    const next = vi.spyOn(api, "nextSuggestion").mockResolvedValue({ suggestion: shown });
    shared(store);
    await vi.waitFor(() => expect(next).toHaveBeenCalledTimes(1));
    expect(store.getState().origin.suggestion).toBe(shown); // the same one: kept as it is
    shared(store); // still shared: not asked again
    expect(next).toHaveBeenCalledTimes(1);
  });

  it("shows the next one when someone else holds it by now, unless the person changed the groups", async () => {
    const { store, controller } = alone();
    await controller.boot("s-demo");
    const shown = store.getState().origin.suggestion!;
    shared(store);
    await vi.waitFor(() => expect(store.getState().origin.suggestion?.id).not.toBe(shown.id));

    const other = alone();
    await other.controller.boot("s-demo");
    const first = other.store.getState().origin.suggestion!;
    other.store.dispatch({ type: "remove", id: first.left[0]!, at: Date.now() });
    const groups = other.store.getState().groups;
    shared(other.store);
    await new Promise((r) => setTimeout(r, 0));
    expect(other.store.getState().groups).toBe(groups);
  });
});

describe("undo in a shared session", () => {
  it("shows the server's refusal of another person's judgement and keeps it", async () => {
    const refusal = "judgement 900 was made by owner; only they can undo it";
    const { store, controller, stream } = setup("groupwise", ANN, {
      undoJudgement: () => Promise.reject(new ApiError(403, refusal)),
    });
    await controller.boot("s-demo");
    stream.handlers!.judgement!(theirs(OWNER, {}), 20);
    const before = store.getState().judgements.length;
    await controller.undo();
    expect(store.getState().toast).toMatchObject({ kind: "error", text: `Not undone: ${refusal}` });
    expect(store.getState().judgements).toHaveLength(before);
    expect(store.getState().annotators.list.find((p) => p.id === "owner")!.comparisons).toBe(4);
  });

  it("takes back this person's own last answer, not a newer one of someone else", async () => {
    const { api, store, controller, stream } = setup("groupwise", ANN);
    const undo = vi.spyOn(api, "undoJudgement");
    await controller.boot("s-demo");
    await controller.answer("left");
    const mine = store.getState().judgements.at(-1)!;
    stream.handlers!.judgement!(theirs(OWNER, { id: mine.id + 1 }), 20);
    await controller.undo();
    expect(undo).toHaveBeenCalledWith("s-demo", mine.id);
  });
});

describe("the counters", () => {
  it("count a judgement event once, whether or not a state with it came first", async () => {
    const { store, controller, stream, base } = setup("groupwise", OWNER);
    await controller.boot("s-demo");
    const state = (await base.session("s-demo")) as Awaited<ReturnType<Api["session"]>> & object;
    stream.handlers!.state!({ ...state, annotators: [person("owner", "owner", 3, 6), person("a-1", "Ann", 1, 2)] }, 10);
    stream.handlers!.judgement!(theirs(ANN, {}), 11);
    const ann = () => store.getState().annotators.list.find((p) => p.id === "a-1")!;
    expect([ann().comparisons, ann().pairs]).toEqual([2, 3]);
    // the state of the same revision holds it already: not counted twice
    stream.handlers!.state!({ ...state, annotators: [person("owner", "owner", 3, 6), person("a-1", "Ann", 2, 3)] }, 11);
    stream.handlers!.judgement!(theirs(ANN, {}), 11);
    expect([ann().comparisons, ann().pairs]).toEqual([2, 3]);
    // undone: its pairs come off with it
    stream.handlers!.judgement!(theirs(ANN, { undone: true, pairs: [] }), 12);
    expect([ann().comparisons, ann().pairs]).toEqual([1, 2]);
  });
});

describe("time shown", () => {
  it("reads the people again every 10 s while a shared round runs on screen, and stops after", async () => {
    vi.useFakeTimers({ toFake: ["setInterval", "clearInterval"] });
    try {
      const { api, store, controller } = setup("groupwise", ANN);
      const read = vi.spyOn(api, "annotators");
      await controller.boot("s-demo");
      expect(read).not.toHaveBeenCalled();
      vi.advanceTimersByTime(10_000);
      expect(read).toHaveBeenCalledTimes(1);
      const s = store.getState().session!;
      store.dispatch({ type: "session", session: { ...s, phase: "training", timer: { ...s.timer, running: false } }, at: 0 });
      vi.advanceTimersByTime(30_000);
      expect(read).toHaveBeenCalledTimes(1);
    } finally {
      vi.useRealTimers();
    }
  });
});

describe("the owner's annotators", () => {
  it("adds a person, keeps their link to copy, and removes them", async () => {
    const { store, controller } = setup("groupwise", OWNER);
    await controller.boot("s-demo");
    expect(await controller.addAnnotator("  Bob  ")).toBe(true);
    const created = store.getState().people.created!;
    expect(created).toMatchObject({ name: "Bob" });
    expect(created.link).toContain(`token=${created.token}`);
    expect(store.getState().annotators.list.map((p) => p.name)).toContain("Bob");
    await controller.removeAnnotator(created.id);
    expect(store.getState().annotators.list.map((p) => p.name)).not.toContain("Bob");
    expect(store.getState().people.created).toBeNull();
  });

  it("says why a name is refused and adds nothing", async () => {
    const { store, controller } = setup("groupwise", OWNER, {
      addAnnotator: () => Promise.reject(new ApiError(409, "session s-demo already has an annotator named 'Ann'")),
    });
    await controller.boot("s-demo");
    expect(await controller.addAnnotator("")).toBe(false);
    expect(store.getState().people.error).toBe("Type the person's name first.");
    expect(await controller.addAnnotator("ann")).toBe(false);
    expect(store.getState().people.error).toBe("session s-demo already has an annotator named 'Ann'");
  });
});
