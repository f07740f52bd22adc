import { describe, expect, it } from "vitest";
import { ancestors, buildTree, treePath } from "../src/lib/tree";
import { FOUR, PADDED } from "./fixtures";

describe("buildTree", () => {
  it("keeps the child order as the leaf order", () => {
    const t = buildTree(PADDED);
    expect(t.leaves.map((l) => l.id)).toEqual(["b2", "b0", "b1", "b4", "b3"]);
    expect(t.nodes.get("m5")!.leaves).toEqual(["b2", "b0", "b1", "b4"]);
    expect(t.levels).toBe(3);
  });

  it("reads clip and poster from the node or from extra", () => {
    const t = buildTree({
      id: "root",
      level: 1,
      children: [
        { id: "b0", level: 0, children: [], clip: "x.mp4" },
        { id: "b1", level: 0, children: [], extra: { clip: "y.mp4", poster: "y.jpg" } },
      ],
    });
    expect(t.nodes.get("b0")!.clip).toBe("x.mp4");
    expect(t.nodes.get("b1")!.clip).toBe("y.mp4");
    expect(t.nodes.get("b1")!.poster).toBe("y.jpg");
  });

  it("links parents, children and depths", () => {
    const t = buildTree(PADDED);
    const padding = t.nodes.get("b3@1")!;
    expect([padding.depth, padding.isLeaf, padding.parent!.id]).toEqual([2, false, "b3@2"]);
    expect(padding.children.map((c) => c.id)).toEqual(["b3"]);
    expect(t.root.children.map((c) => c.id)).toEqual(["m5", "b3@2"]);
    expect(t.leafIndex.get("b4")).toBe(3);
  });

  it("refuses duplicate ids", () => {
    const dup = { id: "root", level: 1, children: [FOUR.children[0]!, FOUR.children[0]!] };
    expect(() => buildTree(dup)).toThrow(/duplicate node id m1/);
  });
});

describe("treePath", () => {
  const t = buildTree(FOUR);
  const ids = (a: string, b: string) => treePath(t, a, b).map((n) => n.id);

  it("goes up to the lowest common ancestor once and down again", () => {
    expect(ids("b0", "b3")).toEqual(["b0", "m1", "root", "m2", "b3"]);
    expect(ids("b0", "b1")).toEqual(["b0", "m1", "b1"]);
    expect(ids("b3", "b2")).toEqual(["b3", "m2", "b2"]);
    expect(ids("b1", "b1")).toEqual(["b1"]);
    expect(() => ids("b1", "b9")).toThrow(/unknown node b9/);
  });

  it("lists ancestors nearest first", () => {
    expect(ancestors(t.nodes.get("b2")!).map((n) => n.id)).toEqual(["m2", "root"]);
  });
});
