import { describe, expect, it } from "vitest";
import { controlPoint, edgePath, edgePoints, flattenEdge, segmentBins } from "../src/lib/edges";
import { midAngle, polar, radialLayout } from "../src/lib/layout";
import { buildTree } from "../src/lib/tree";
import { FOUR } from "./fixtures";

const tree = buildTree(FOUR);
const layout = radialLayout(tree, { radius: 100, disc: 0.5, ringGap: 0, leafWeight: 1, arcGap: 0, edgeGap: 10 });

function numbers(path: string): number[] {
  return (path.match(/-?\d+(\.\d+)?(e-?\d+)?/g) ?? []).map(Number);
}

describe("edge routing", () => {
  it("routes through the lowest common ancestor: the root sits at the centre", () => {
    const pts = edgePoints(tree, layout, "b0", "b3");
    expect(pts).toHaveLength(5);
    expect(pts[2]).toEqual([0, 0]);
    const [x, y] = polar(midAngle(layout.byId.get("b0")!), 40);
    expect(pts[0]![0]).toBeCloseTo(x);
    expect(pts[0]![1]).toBeCloseTo(y);
  });

  it("places an inner node on its angle, nearer the centre the higher its level", () => {
    const m1 = controlPoint(tree, layout, tree.nodes.get("m1")!);
    const [x, y] = polar(Math.PI / 2, 20); // m1 spans [0, pi]; edgeRadius 40 · (2 − 1) / 2
    expect(m1[0]).toBeCloseTo(x);
    expect(m1[1]).toBeCloseTo(y);
  });

  it("siblings meet at their parent, not at the root", () => {
    const pts = edgePoints(tree, layout, "b0", "b1");
    expect(pts).toHaveLength(3);
    expect(pts[1]).toEqual(controlPoint(tree, layout, tree.nodes.get("m1")!));
  });

  it("draws a bundled curve from one leaf to the other", () => {
    const pts = edgePoints(tree, layout, "b0", "b3");
    const d = edgePath(pts, 0.85);
    expect(d.startsWith("M")).toBe(true);
    const n = numbers(d);
    expect(n[0]).toBeCloseTo(pts[0]![0]);
    expect(n[1]).toBeCloseTo(pts[0]![1]);
    expect(n[n.length - 2]).toBeCloseTo(pts[4]![0]);
    expect(n[n.length - 1]).toBeCloseTo(pts[4]![1]);
  });

  it("beta 0 is a straight line; stronger bundling pulls the curve towards the LCA", () => {
    const pts = edgePoints(tree, layout, "b0", "b3"); // not opposite: the chord misses the centre
    const straight = numbers(edgePath(pts, 0));
    // every coordinate pair of the beta-0 path lies on the chord from b0 to b2
    const [x0, y0] = pts[0]!;
    const [x1, y1] = pts[pts.length - 1]!;
    for (let i = 0; i < straight.length; i += 2) {
      const cross = (x1 - x0) * (straight[i + 1]! - y0) - (y1 - y0) * (straight[i]! - x0);
      // distance from the chord; d3 writes path numbers with 3 decimals
      expect(Math.abs(cross) / Math.hypot(x1 - x0, y1 - y0)).toBeLessThan(2e-3);
    }
    const dist = (p: number[]) => {
      let best = Infinity;
      for (let i = 0; i < p.length; i += 2) best = Math.min(best, Math.hypot(p[i]!, p[i + 1]!));
      return best;
    };
    expect(dist(numbers(edgePath(pts, 1)))).toBeLessThan(dist(numbers(edgePath(pts, 0.5))));
  });
});

describe("drawing helpers", () => {
  it("flattens the bundled curve into a polyline from one leaf to the other", () => {
    const pts = edgePoints(tree, layout, "b0", "b3");
    const line = flattenEdge(pts, 0.85, 4);
    expect(line[0]![0]).toBeCloseTo(pts[0]![0]);
    expect(line[0]![1]).toBeCloseTo(pts[0]![1]);
    expect(line[line.length - 1]![0]).toBeCloseTo(pts[4]![0]);
    expect(line[line.length - 1]![1]).toBeCloseTo(pts[4]![1]);
    expect(line.length).toBeGreaterThan(pts.length);
  });

  it("bins segments by their position along the line", () => {
    // four equal segments into two bins: the first half and the second half
    const line: [number, number][] = [[0, 0], [1, 0], [2, 0], [3, 0], [4, 0]];
    expect([...segmentBins(line, 2)]).toEqual([0, 0, 1, 1]);
    // a long last segment: its middle lies past the first three quarters
    expect([...segmentBins([[0, 0], [1, 0], [2, 0], [10, 0]], 4)]).toEqual([0, 0, 2]);
    expect([...segmentBins([[0, 0]], 3)]).toEqual([]);
  });
});
