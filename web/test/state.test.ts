import { describe, expect, it } from "vitest";
import type { JudgementOut } from "../src/api";
import { buildTree } from "../src/lib/tree";
import { type State, comparedLeaves, createStore, initialState, reduce } from "../src/state";
import { FOUR } from "./fixtures";

const round = { sid: "s-1", round: 0, tree: buildTree(FOUR), medoids: {} };

function judgement(id: number, left: string[], right: string[]): JudgementOut {
  return {
    id,
    client_id: `c${id}`,
    round: 0,
    left,
    right,
    label: "left",
    source: "explored",
    seconds: 3,
    edits: 1,
    annotator: { id: "owner", name: "owner" },
    created_at: "",
    undone: false,
    pairs: left.map((a, i) => ({ a, b: right[i % right.length]!, label: 1 })),
  };
}

const withRound = (): State => reduce(initialState, { type: "round-data", round });

describe("reducer", () => {
  it("counts edits and starts the clock with the first selection", () => {
    let s = withRound();
    s = reduce(s, { type: "select", click: { leaves: ["b0", "b1"], isLeaf: false, add: false }, other: false, at: 1000 });
    s = reduce(s, { type: "select", click: { leaves: ["b2"], isLeaf: true, add: false }, other: true, at: 2000 });
    expect(s.groups).toEqual({ A: ["b0", "b1"], B: ["b2"] });
    expect(s.origin).toMatchObject({ source: "explored", edits: 2, startedAt: 1000 });
  });

  it("resets the origin when the groups become empty", () => {
    let s = withRound();
    s = reduce(s, { type: "select", click: { leaves: ["b0"], isLeaf: true, add: false }, other: false, at: 5 });
    s = reduce(s, { type: "remove", id: "b0", at: 6 });
    expect(s.origin.startedAt).toBeNull();
    expect(s.origin.edits).toBe(0);
  });

  it("shows why a selection was refused and keeps the groups", () => {
    const s = withRound();
    const many = Array.from({ length: 9 }, (_, i) => `b${i}`);
    const t = reduce(s, { type: "select", click: { leaves: many, isLeaf: false, add: false }, other: false, at: 0 });
    expect(t.groups).toBe(s.groups);
    expect(t.toast?.kind).toBe("info");
  });

  it("switches the target group", () => {
    const s = reduce(initialState, { type: "target", group: "switch" });
    expect(s.target).toBe("B");
    expect(reduce(s, { type: "target", group: "switch" }).target).toBe("A");
  });

  it("clears the groups after an answer and offers undo", () => {
    let s = withRound();
    s = reduce(s, { type: "set-groups", groups: { A: ["b0"], B: ["b3"] }, origin: { source: "suggested", edits: 0, startedAt: 1, suggestion: null } });
    s = reduce(s, { type: "submitting", value: true });
    s = reduce(s, { type: "answered", judgement: judgement(7, ["b0"], ["b3"]) });
    expect(s.groups).toEqual({ A: [], B: [] });
    expect(s.submitting).toBe(false);
    expect(s.judgements.map((j) => j.id)).toEqual([7]);
    expect(s.toast).toMatchObject({ kind: "ok", undo: true, text: "Saved: left better · 1 preference pair." });
  });

  it("keeps judgements unique and ordered whichever way they arrive", () => {
    let s = withRound();
    s = reduce(s, { type: "judgement-stored", judgement: judgement(2, ["b0"], ["b1"]) });
    s = reduce(s, { type: "judgement-stored", judgement: judgement(1, ["b2"], ["b3"]) });
    s = reduce(s, { type: "judgement-stored", judgement: judgement(2, ["b0"], ["b1"]) });
    expect(s.judgements.map((j) => j.id)).toEqual([1, 2]);
    s = reduce(s, { type: "judgement-undone", id: 1 });
    expect(s.judgements.map((j) => j.id)).toEqual([2]);
    expect([...comparedLeaves(s.judgements)].sort()).toEqual(["b0", "b1"]);
  });

  it("drops judgements of another round", () => {
    const s = withRound();
    const j = { ...judgement(3, ["b0"], ["b1"]), round: 4 };
    expect(reduce(s, { type: "judgement-stored", judgement: j })).toBe(s);
  });

  it("resets the selection for a new round, not for the same one again", () => {
    let s = withRound();
    s = reduce(s, { type: "set-groups", groups: { A: ["b0"], B: [] }, origin: initialState.origin });
    expect(reduce(s, { type: "round-data", round: { ...round } }).groups.A).toEqual(["b0"]);
    expect(reduce(s, { type: "round-data", round: { ...round, round: 1 } }).groups.A).toEqual([]);
  });
});

describe("store", () => {
  it("notifies subscribers only on change", () => {
    const store = createStore();
    const seen: string[] = [];
    const off = store.subscribe((s) => seen.push(s.target));
    store.dispatch({ type: "target", group: "B" });
    store.dispatch({ type: "hover", id: null, from: null }); // no change
    off();
    store.dispatch({ type: "target", group: "A" });
    expect(seen).toEqual(["B"]);
  });
});
