import { describe, expect, it } from "vitest";
import { GROUP_COLOURS, groupTint, mix, suggestionAlpha, withAlpha } from "../src/lib/colour";

describe("colour mixing", () => {
  it("leaves an arc neutral when none of its leaves is selected", () => {
    expect(groupTint("#cccccc", 0, 0, 10)).toBe("#cccccc");
  });

  it("tints fully when all leaves are in one group", () => {
    expect(groupTint("#cccccc", 4, 0, 4)).toBe(GROUP_COLOURS.A.toLowerCase());
    expect(groupTint("#cccccc", 0, 3, 3)).toBe(GROUP_COLOURS.B.toLowerCase());
  });

  it("tints in proportion to the selected leaves", () => {
    // half of #ffffff and #000000 → #808080 (rounded)
    expect(mix([["#ffffff", 1], ["#000000", 1]])).toBe("#808080");
    // a quarter in A: 3/4 neutral white, 1/4 #E69F00
    const c = groupTint("#ffffff", 1, 0, 4);
    expect(c).toBe(mix([["#ffffff", 3], [GROUP_COLOURS.A, 1]]));
    expect(c).toBe("#f9e7bf"); // (3·255 + 230) / 4 = 248.75 → f9
  });

  it("mixes both groups when a parent holds leaves of each", () => {
    expect(groupTint("#000000", 1, 1, 2)).toBe(mix([[GROUP_COLOURS.A, 1], [GROUP_COLOURS.B, 1]]));
  });

  it("makes stronger suggestions more opaque, within (0, 1]", () => {
    expect(suggestionAlpha(1)).toBeGreaterThan(suggestionAlpha(0.2));
    expect(suggestionAlpha(5)).toBeLessThanOrEqual(1);
    expect(suggestionAlpha(0)).toBeGreaterThan(0);
    expect(withAlpha("#ff0000", 0.5)).toBe("rgba(255, 0, 0, 0.5)");
  });
});
