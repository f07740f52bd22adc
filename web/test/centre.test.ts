import { describe, expect, it } from "vitest";
import { rng } from "../bench/synthetic";
import { arcPx, canCentre, centreNode, centresOn, crumbs, gesturesToPick, outward } from "../src/lib/centre";
import { radialLayout } from "../src/lib/layout";
import { MAX_GROUP } from "../src/lib/selection";
import { type TreeJson, buildTree } from "../src/lib/tree";
import { initialState, reduce } from "../src/state";
import { FOUR, PADDED } from "./fixtures";

const TAU = 2 * Math.PI;

/**
 * A 1,000-behaviour tree as lopsided as the round (top clusters of 348, 138, 14,
 * 147, 30, 76 and 247 behaviours), four levels, each cluster split at random into 2–6.
 */
function lopsided(seed = 5): TreeJson {
  const rand = rng(seed);
  let next = 0;
  let merges = 0;
  const split = (n: number, level: number): TreeJson => {
    if (level === 0) {
      const i = next++;
      return { id: `b${i}`, level: 0, children: [], behaviour: i };
    }
    if (n === 1) {
      const child = split(1, level - 1);
      return { id: `${child.id.split("@")[0]}@${level}`, level, children: [child] };
    }
    const parts = level === 1 ? Array<number>(n).fill(1) : cut(n, Math.min(n, 2 + Math.floor(rand() * 5)));
    return { id: `m${++merges}`, level, children: parts.map((m) => split(m, level - 1)) };
  };
  /** n into k positive parts of random shares. */
  const cut = (n: number, k: number): number[] => {
    const w = Array.from({ length: k }, () => 0.2 + rand());
    const total = w.reduce((a, b) => a + b, 0);
    const parts = w.map((x) => Math.max(1, Math.floor((x / total) * n)));
    parts[0]! += n - parts.reduce((a, b) => a + b, 0);
    return parts;
  };
  const top = [348, 138, 14, 147, 30, 76, 247];
  return { id: "root", level: 4, children: top.map((n) => split(n, 3)) };
}

describe("the chart's centre", () => {
  const tree = buildTree(PADDED);

  it("lays a centred cluster's leaves over the whole ring, its children's level outermost", () => {
    const layout = radialLayout(tree, { radius: 100, arcGap: 0, centre: tree.nodes.get("m6")! });
    expect(layout.centre.id).toBe("m6");
    expect(layout.levels).toBe(1);
    expect(layout.rings.map((r) => r.map((a) => a.node.id))).toEqual([["b2", "b0", "b1"]]);
    expect(layout.byId.get("b2")!.start).toBe(0);
    expect(layout.byId.get("b1")!.end).toBeCloseTo(TAU);
    expect(layout.byId.has("m6")).toBe(false); // the centre itself is not drawn
    expect(layout.byId.has("b4")).toBe(false); // nor anything outside it
  });

  it("names the root for no centre, an unknown id, a leaf or a padding node", () => {
    for (const id of [null, "nope", "b3", "b4@1"]) expect(centreNode(tree, id).id).toBe("root");
    expect(centreNode(tree, "m5").id).toBe("m5");
    expect(canCentre(tree.nodes.get("b3@2")!)).toBe(false);
  });

  it("leads back out by a breadcrumb and one step at a time, padding skipped", () => {
    expect(crumbs(tree, "m6").map((n) => n.id)).toEqual(["root", "m5", "m6"]);
    expect(crumbs(tree, null).map((n) => n.id)).toEqual(["root"]);
    expect(outward(tree, "m6")).toBe("m5");
    expect(outward(tree, "m5")).toBeNull();
    expect(outward(tree, null)).toBeNull();
  });

  it("centres on a plain click on a cluster too big for a group, never on a leaf or with Shift", () => {
    const big = Array.from({ length: MAX_GROUP + 1 }, (_, i) => `b${i}`);
    expect(centresOn({ leaves: big, isLeaf: false, add: false })).toBe(true);
    expect(centresOn({ leaves: big, isLeaf: false, add: true })).toBe(false);
    expect(centresOn({ leaves: big.slice(0, MAX_GROUP), isLeaf: false, add: false })).toBe(false);
    expect(centresOn({ leaves: ["b1"], isLeaf: true, add: false })).toBe(false);
  });

  it("in the store: a big cluster's click centres, a new round starts whole, hover cleared", () => {
    const big = Array.from({ length: 20 }, (_, i) => `b${i}`);
    let s = reduce(initialState, { type: "hover", id: "m3", from: "chart" });
    s = reduce(s, { type: "select", click: { id: "m3", leaves: big, isLeaf: false, add: false }, other: true, at: 1 });
    expect(s.centre).toBe("m3");
    expect(s.groups).toEqual({ A: [], B: [] });
    expect(s.toast).toBeNull();
    expect(s.hover.id).toBeNull();
    s = reduce(s, { type: "centre", id: null });
    expect(s.centre).toBeNull();
    s = reduce(s, { type: "centre", id: "m3" });
    const round = { sid: "s", round: 2, tree: buildTree(FOUR), medoids: {} };
    expect(reduce(s, { type: "round-data", round }).centre).toBeNull();
  });
});

describe("picking one behaviour of 1,000", () => {
  const tree = buildTree(lopsided());
  // The chart at 60 % of a 768 px screen, as the app draws it (viewBox 1000, radius 480).
  const geometry = { scale: 461 / 1000, layout: { radius: 480 }, minPx: 6, maxZoom: 16 };

  it("takes a leaf under a pixel wide in the whole round", () => {
    const layout = radialLayout(tree, { radius: 480 });
    expect(tree.leaves.length).toBe(1000);
    expect(arcPx(layout.byId.get("b0")!, geometry.scale)).toBeLessThan(1);
  });

  it("takes at most 3 gestures for every leaf (centre, zoom if needed, click)", () => {
    const layouts = new Map();
    const counts = tree.leaves.map((leaf) => gesturesToPick(tree, leaf.id, geometry, layouts));
    // the layouts kept between the counts are the ones laid out afresh for each
    const afresh = tree.leaves.slice(0, 50).map((leaf) => gesturesToPick(tree, leaf.id, geometry));
    expect(counts.slice(0, 50)).toEqual(afresh);
    expect(Math.max(...counts)).toBeLessThanOrEqual(3);
    expect(Math.min(...counts)).toBe(2); // none can be picked in the whole round
  });

  it("counts a zoom when centring cannot make a leaf wide enough, and gives up past the zoom", () => {
    const flat: TreeJson = {
      id: "root",
      level: 1,
      children: Array.from({ length: 1000 }, (_, i) => ({ id: `b${i}`, level: 0, children: [] })),
    };
    const t = buildTree(flat);
    expect(gesturesToPick(t, "b5", geometry)).toBe(2); // zoom, click
    expect(gesturesToPick(t, "b5", { ...geometry, maxZoom: 2 })).toBe(Number.POSITIVE_INFINITY);
    expect(() => gesturesToPick(t, "b5000", geometry)).toThrow(/unknown behaviour b5000/);
  });
});
