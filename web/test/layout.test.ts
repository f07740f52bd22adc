import { describe, expect, it } from "vitest";
import { DEFAULT_LAYOUT, arcAt, midAngle, neighbourArc, polar, radialLayout } from "../src/lib/layout";
import { buildTree } from "../src/lib/tree";
import { FOUR, PADDED } from "./fixtures";

const TAU = 2 * Math.PI;

describe("radialLayout", () => {
  const layout = radialLayout(buildTree(FOUR), { radius: 100, disc: 0.5, ringGap: 0, leafWeight: 1, arcGap: 0 });

  it("puts leaves in the innermost ring and parents outside; the root is not drawn", () => {
    expect(layout.rings.map((r) => r.map((a) => a.node.id))).toEqual([
      ["b0", "b1", "b2", "b3"],
      ["m1", "m2"],
    ]);
    expect(layout.byId.has("root")).toBe(false);
    const leafRing = layout.byId.get("b0")!;
    const parentRing = layout.byId.get("m1")!;
    expect(leafRing.r0).toBeCloseTo(50);
    expect(leafRing.r1).toBeCloseTo(75);
    expect(parentRing.r0).toBeCloseTo(75);
    expect(parentRing.r1).toBeCloseTo(100);
    expect(layout.discRadius).toBeCloseTo(50);
  });

  it("gives every leaf the same angle and a parent the span of its leaves", () => {
    const b = (id: string) => layout.byId.get(id)!;
    expect([b("b0").start, b("b0").end]).toEqual([0, TAU / 4]);
    expect(b("b3").end).toBeCloseTo(TAU);
    expect([b("m1").start, b("m1").end]).toEqual([0, TAU / 2]);
    expect(midAngle(b("m2"))).toBeCloseTo((3 * TAU) / 4);
  });

  it("draws the outer rings first (leaves on top)", () => {
    expect(layout.arcs.map((a) => a.ring)).toEqual([1, 1, 0, 0, 0, 0]);
  });

  it("pads arcs inside their span by the arc gap", () => {
    const padded = radialLayout(buildTree(FOUR), { ...DEFAULT_LAYOUT, radius: 100, arcGap: 2 });
    const a = padded.byId.get("b1")!;
    expect(a.a0).toBeGreaterThan(a.start);
    expect(a.a1).toBeLessThan(a.end);
    expect(a.a1 - a.a0).toBeGreaterThan(0.7 * (a.end - a.start));
  });

  it("draws padding nodes in their level's ring over the same angle as their child", () => {
    const p = radialLayout(buildTree(PADDED), { radius: 100 });
    expect(p.rings.length).toBe(3);
    expect(p.rings[1]!.map((a) => a.node.id)).toEqual(["m6", "b4@1", "b3@1"]);
    expect(p.rings[2]!.map((a) => a.node.id)).toEqual(["m5", "b3@2"]);
    const leaf = p.byId.get("b4")!;
    const pad = p.byId.get("b4@1")!;
    expect([pad.start, pad.end]).toEqual([leaf.start, leaf.end]);
  });

  it("measures angles clockwise from 12 o'clock", () => {
    const [x0, y0] = polar(0, 10);
    expect(x0).toBeCloseTo(0);
    expect(y0).toBeCloseTo(-10);
    const [x1, y1] = polar(Math.PI / 2, 10);
    expect(x1).toBeCloseTo(10);
    expect(y1).toBeCloseTo(0);
  });
});

describe("keyboard navigation between arcs", () => {
  const layout = radialLayout(buildTree(FOUR), { radius: 100 });
  const at = (id: string) => layout.byId.get(id)!;
  const go = (id: string, key: string) => neighbourArc(layout, at(id), key);

  it("moves along a ring, wrapping, and to its ends", () => {
    expect(go("b0", "ArrowRight")!.node.id).toBe("b1");
    expect(go("b3", "ArrowRight")!.node.id).toBe("b0");
    expect(go("b0", "ArrowLeft")!.node.id).toBe("b3");
    expect(go("m2", "Home")!.node.id).toBe("m1");
    expect(go("b1", "End")!.node.id).toBe("b3");
  });

  it("goes out to the enclosing arc and in to the first child, never to the root", () => {
    expect(go("b2", "ArrowUp")!.node.id).toBe("m2");
    expect(go("m2", "ArrowDown")!.node.id).toBe("b2");
    expect(go("m1", "ArrowUp")).toBeNull();
    expect(go("b0", "ArrowDown")).toBeNull();
    expect(go("b0", "x")).toBeUndefined();
  });
});

describe("arcAt", () => {
  const layout = radialLayout(buildTree(FOUR), { radius: 100, disc: 0.5, ringGap: 4, leafWeight: 1, arcGap: 2 });
  const at = (angle: number, r: number) => arcAt(layout, ...polar(angle, r))?.node.id ?? null;
  const b0 = layout.byId.get("b0")!;
  const m2 = layout.byId.get("m2")!;

  it("finds the arc under a point of each ring", () => {
    expect(at(midAngle(b0), (b0.r0 + b0.r1) / 2)).toBe("b0");
    expect(at(TAU * 0.6, (m2.r0 + m2.r1) / 2)).toBe("m2");
    expect(at(TAU * 0.99, b0.r1 - 1)).toBe("b3");
  });

  it("gives the gaps between neighbours and near a ring's edge to an arc", () => {
    expect(at(b0.end - 1e-6, (b0.r0 + b0.r1) / 2)).toBe("b0"); // inside b0's padding
    expect(at(b0.end + 1e-6, (b0.r0 + b0.r1) / 2)).toBe("b1");
    expect(at(midAngle(m2), m2.r1 + 1.5)).toBe("m2");
  });

  it("finds nothing in the disc or beyond the outer ring", () => {
    expect(at(1, 10)).toBeNull();
    expect(at(1, b0.r0 - 3)).toBeNull();
    expect(at(1, 104)).toBeNull();
  });
});
