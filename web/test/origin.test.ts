import { describe, expect, it } from "vitest";
import type { Suggestion } from "../src/api";
import { FRESH_ORIGIN, type Origin, arcChange, originAfter, suggestedOrigin } from "../src/lib/origin";
import { type Groups, clickArc, moveLeaf, removeLeaf } from "../src/lib/selection";
import { initialState, reduce } from "../src/state";

const suggestion: Suggestion = { id: 1, left: ["b1", "b2"], right: ["b3"], left_node: "m1", right_node: "b3", score: 0.5 };
const loaded: Groups = { A: ["b1", "b2"], B: ["b3"] };
const cluster = (leaves: string[], target: "A" | "B", add = false) =>
  ({ leaves, isLeaf: false, target, add }) as const;
const leaf = (id: string, target: "A" | "B", add = false) => ({ leaves: [id], isLeaf: true, target, add }) as const;

/** Applies clicks to the loaded suggestion as the page does: the selection, then the origin. */
function walk(origin: Origin, groups: Groups, clicks: ReturnType<typeof cluster | typeof leaf>[]) {
  let at = 100;
  for (const click of clicks) {
    const r = clickArc(groups, click);
    if (r.changed) origin = originAfter(origin, arcChange(click), r.groups, (at += 1));
    groups = r.groups;
  }
  return { origin, groups };
}

describe("where a comparison comes from", () => {
  it("a suggestion loaded into the groups is suggested, no edits, clock started", () => {
    expect(suggestedOrigin(suggestion, 50)).toEqual({ source: "suggested", edits: 0, startedAt: 50, suggestion });
  });

  it("edits keep a suggestion suggested and count one each", () => {
    let o = suggestedOrigin(suggestion, 50);
    let g = loaded;
    for (const next of [removeLeaf(g, "b2").groups, moveLeaf(removeLeaf(g, "b2").groups, "b1").groups]) {
      o = originAfter(o, "edit", next, 60);
      g = next;
    }
    expect(o).toMatchObject({ source: "suggested", edits: 2, startedAt: 50 });
  });

  it("adding single behaviours, adding a cluster with the modifier and taking one out are edits", () => {
    expect(arcChange(leaf("b7", "A"))).toBe("edit");
    expect(arcChange(leaf("b1", "A", true))).toBe("edit"); // takes it out
    expect(arcChange(cluster(["b7", "b8"], "B", true))).toBe("edit");
    const { origin } = walk(suggestedOrigin(suggestion, 50), loaded, [
      leaf("b7", "A"),
      cluster(["b8", "b9"], "B", true),
      leaf("b1", "A", true),
    ]);
    expect(origin).toMatchObject({ source: "suggested", edits: 3 });
  });

  it("a cluster click that replaces a group's members makes the comparison the person's own", () => {
    expect(arcChange(cluster(["b5", "b6"], "A"))).toBe("fill");
    expect(arcChange(cluster(["b2", "b6"], "A"))).toBe("fill"); // partly in A: replaces
    // The walk: A by a click, B by Alt-click, one clip moved, one removed.
    const { origin, groups } = walk(suggestedOrigin(suggestion, 50), loaded, [
      cluster(["b5", "b6"], "A"),
      cluster(["b7", "b8"], "B"),
    ]);
    let o = originAfter(origin, "edit", moveLeaf(groups, "b5").groups, 200);
    o = originAfter(o, "edit", removeLeaf(moveLeaf(groups, "b5").groups, "b8").groups, 201);
    expect(o).toMatchObject({ source: "explored", edits: 4, startedAt: 50, suggestion });
  });

  it("stays explored after a fill, whatever follows", () => {
    const { origin } = walk(suggestedOrigin(suggestion, 50), loaded, [
      cluster(["b5", "b6"], "A"),
      leaf("b1", "B", true),
    ]);
    expect(origin.source).toBe("explored");
  });

  it("groups built from empty are explored; emptied groups start afresh", () => {
    const o = originAfter(FRESH_ORIGIN, "edit", { A: ["b1"], B: [] }, 7);
    expect(o).toEqual({ source: "explored", edits: 1, startedAt: 7, suggestion: null });
    expect(originAfter(suggestedOrigin(suggestion, 5), "edit", { A: [], B: [] }, 9)).toBe(FRESH_ORIGIN);
  });

  it("the store applies the rule to chart clicks", () => {
    let s = reduce(initialState, { type: "set-groups", groups: loaded, origin: suggestedOrigin(suggestion, 1) });
    s = reduce(s, { type: "remove", id: "b2", at: 2 });
    expect(s.origin).toMatchObject({ source: "suggested", edits: 1 });
    s = reduce(s, { type: "select", click: { leaves: ["b5", "b6"], isLeaf: false, add: false }, other: true, at: 3 });
    expect(s.groups).toEqual({ A: ["b1"], B: ["b5", "b6"] });
    expect(s.origin).toMatchObject({ source: "explored", edits: 2 });
  });
});
