import { describe, expect, it } from "vitest";
import { guideKey, guideSeen, rememberGuideSeen } from "../src/lib/guide";
import { placeBeside } from "../src/lib/tooltip";

function memoryStorage() {
  const items = new Map<string, string>();
  return {
    getItem: (k: string) => items.get(k) ?? null,
    setItem: (k: string, v: string) => void items.set(k, v),
    items,
  };
}

describe("guide memory", () => {
  it("shows the guide until it was closed once, per mode", () => {
    const storage = memoryStorage();
    expect(guideSeen(storage, "groupwise")).toBe(false);
    rememberGuideSeen(storage, "groupwise");
    expect(guideSeen(storage, "groupwise")).toBe(true);
    expect(guideSeen(storage, "pairwise")).toBe(false);
    expect(storage.items.get(guideKey("groupwise"))).toBe("1");
  });

  it("shows the guide when storage is missing or refuses", () => {
    const broken = {
      getItem: () => {
        throw new Error("denied");
      },
      setItem: () => {
        throw new Error("denied");
      },
    };
    expect(guideSeen(null, "groupwise")).toBe(false);
    expect(guideSeen(broken, "groupwise")).toBe(false);
    expect(() => rememberGuideSeen(broken, "groupwise")).not.toThrow();
  });
});

describe("placeBeside", () => {
  const chart = { left: 10, top: 100, right: 650, bottom: 650 };

  it("goes right of and below the pointer when it fits", () => {
    expect(placeBeside(100, 200, 236, 290, chart)).toEqual({ left: 118, top: 218 });
  });

  it("flips left of the pointer rather than leave the chart (the answer buttons lie right of it)", () => {
    expect(placeBeside(600, 200, 236, 290, chart)).toEqual({ left: 346, top: 218 });
  });

  it("flips above the pointer near the bottom, and clamps into the chart", () => {
    expect(placeBeside(100, 600, 236, 290, chart)).toEqual({ left: 118, top: 292 });
    expect(placeBeside(100, 300, 236, 290, chart).top).toBeGreaterThanOrEqual(100);
    expect(placeBeside(300, 120, 236, 600, chart)).toEqual({ left: 318, top: 100 });
  });

  it("stays inside the bounds whatever the pointer", () => {
    for (const [x, y] of [[0, 0], [700, 700], [330, 380], [640, 110]] as const) {
      const { left, top } = placeBeside(x, y, 236, 290, chart);
      expect(left).toBeGreaterThanOrEqual(chart.left);
      expect(left + 236).toBeLessThanOrEqual(chart.right);
      expect(top).toBeGreaterThanOrEqual(chart.top);
      expect(top + 290).toBeLessThanOrEqual(chart.bottom);
    }
  });
});
