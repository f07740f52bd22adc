import { describe, expect, it } from "vitest";
import {
  EMPTY_GROUPS,
  type Groups,
  MAX_GROUP,
  clickArc,
  fromSuggestion,
  groupCounts,
  moveLeaf,
  removeLeaf,
} from "../src/lib/selection";

const leaf = (id: string, target: "A" | "B" = "A", add = false) =>
  ({ leaves: [id], isLeaf: true, target, add }) as const;
const arc = (leaves: string[], target: "A" | "B" = "A", add = false) =>
  ({ leaves, isLeaf: false, target, add }) as const;
const ids = (n: number, from = 0) => Array.from({ length: n }, (_, i) => `b${from + i}`);

describe("clicking arcs", () => {
  it("puts a parent's leaves in the target group, replacing it", () => {
    const g: Groups = { A: ["b9"], B: [] };
    const r = clickArc(g, arc(["b1", "b2"]));
    expect(r.groups).toEqual({ A: ["b1", "b2"], B: [] });
    expect(r.changed).toBe(true);
  });

  it("adds with the modifier", () => {
    const r = clickArc({ A: ["b9"], B: [] }, arc(["b1", "b9"], "A", true));
    expect(r.groups.A).toEqual(["b9", "b1"]);
  });

  it("takes leaves out of the other group: never in both", () => {
    const r = clickArc({ A: ["b1"], B: ["b2", "b3"] }, arc(["b2", "b4"], "A"));
    expect(r.groups).toEqual({ A: ["b2", "b4"], B: ["b3"] });
  });

  it("fills the other group when targeted", () => {
    const r = clickArc({ A: ["b1"], B: [] }, arc(["b1", "b2"], "B"));
    expect(r.groups).toEqual({ A: [], B: ["b1", "b2"] });
  });

  it("adds an unselected leaf; a plain click on a selected one changes nothing and says so", () => {
    let g = clickArc(EMPTY_GROUPS, leaf("b1")).groups;
    g = clickArc(g, leaf("b2")).groups;
    expect(g.A).toEqual(["b1", "b2"]);
    const again = clickArc(g, leaf("b1"));
    expect(again.groups).toBe(g);
    expect(again.changed).toBe(false);
    expect(again.message).toMatch(/b1 is in group A already; Shift-click it or its × takes it out/);
  });

  it("takes a leaf out of its group with the modifier (its own gesture), from either group", () => {
    const g: Groups = { A: ["b1", "b3"], B: ["b2"] };
    expect(clickArc(g, leaf("b1", "A", true)).groups).toEqual({ A: ["b3"], B: ["b2"] });
    expect(clickArc(g, leaf("b2", "A", true)).groups).toEqual({ A: ["b1", "b3"], B: [] });
    // …and adds a leaf in no group, as a plain click does
    expect(clickArc(g, leaf("b4", "B", true)).groups).toEqual({ A: ["b1", "b3"], B: ["b2", "b4"] });
  });

  it("moves a leaf of the other group into the target group on a plain click", () => {
    const g: Groups = { A: ["b1"], B: ["b2"] };
    expect(clickArc(g, leaf("b2", "A")).groups).toEqual({ A: ["b1", "b2"], B: [] });
  });

  it("never empties a group by clicking the cluster it already is (issue 40)", () => {
    const g: Groups = { A: ["b1", "b2"], B: ["b5"] };
    const r = clickArc(g, arc(["b1", "b2"]));
    expect(r.groups).toBe(g);
    expect(r.changed).toBe(false);
    expect(r.message).toBe("Group A holds these 2 behaviours already.");
    // with the modifier (add) too
    expect(clickArc(g, arc(["b2", "b1"], "A", true)).groups).toBe(g);
  });

  it("replaces a group that holds more than the clicked cluster with the cluster", () => {
    const r = clickArc({ A: ["b1", "b2", "b3"], B: [] }, arc(["b1", "b2"]));
    expect(r.groups.A).toEqual(["b1", "b2"]);
  });

  it(`refuses more than ${MAX_GROUP} behaviours, leaving the groups unchanged`, () => {
    const g: Groups = { A: ids(6), B: [] };
    const r = clickArc(g, arc(ids(3, 10), "A", true));
    expect(r.changed).toBe(false);
    expect(r.groups).toBe(g);
    expect(r.message).toMatch(/at most 8 behaviours; this would make 9/);
    const big = clickArc(EMPTY_GROUPS, arc(ids(12)));
    expect(big.message).toMatch(/cluster has 12 behaviours/);
    const full: Groups = { A: ids(8), B: [] };
    expect(clickArc(full, leaf("b20")).message).toMatch(/at most 8/);
  });

  it("reports no change for a click that changes nothing", () => {
    expect(clickArc(EMPTY_GROUPS, arc([])).changed).toBe(false);
  });
});

describe("moving and removing", () => {
  it("moves a leaf to the other group, appended", () => {
    expect(moveLeaf({ A: ["b1", "b2"], B: ["b3"] }, "b1").groups).toEqual({ A: ["b2"], B: ["b3", "b1"] });
    expect(moveLeaf({ A: ["b1"], B: ["b3"] }, "b3").groups).toEqual({ A: ["b1", "b3"], B: [] });
  });

  it("refuses to move into a full group", () => {
    const r = moveLeaf({ A: ["b0"], B: ids(8, 1) }, "b0");
    expect(r.changed).toBe(false);
    expect(r.message).toMatch(/Group B can hold at most 8/);
  });

  it("removes a leaf from whichever group holds it", () => {
    expect(removeLeaf({ A: ["b1"], B: ["b2"] }, "b2").groups).toEqual({ A: ["b1"], B: [] });
  });
});

describe("suggestions and counts", () => {
  it("makes disjoint groups of at most 8 from a suggestion", () => {
    const g = fromSuggestion(["b1", "b1", "b2"], ["b2", "b3", ...ids(10, 20)]);
    expect(g.A).toEqual(["b1", "b2"]);
    expect(g.B).toHaveLength(8);
    expect(g.B).not.toContain("b2");
  });

  it("counts each group's leaves under every node", () => {
    const parents: Record<string, string[]> = { b0: ["m1", "root"], b1: ["m1", "root"], b2: ["m2", "root"] };
    const c = groupCounts({ A: ["b0", "b1"], B: ["b2"] }, (l) => parents[l] ?? []);
    expect(c.get("m1")).toEqual({ A: 2, B: 0 });
    expect(c.get("root")).toEqual({ A: 2, B: 1 });
    expect(c.get("b2")).toEqual({ A: 0, B: 1 });
    expect(c.has("m3")).toBe(false);
  });
});
