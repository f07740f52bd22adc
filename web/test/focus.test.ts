import { describe, expect, it } from "vitest";
import { focusAfterLeaving, trapStep } from "../src/lib/focus";

describe("trapStep", () => {
  it("moves to the next control and wraps from the last to the first", () => {
    expect(trapStep(0, 2, false)).toBe(1);
    expect(trapStep(1, 2, false)).toBe(0);
  });

  it("moves backwards with Shift and wraps from the first to the last", () => {
    expect(trapStep(1, 3, true)).toBe(0);
    expect(trapStep(0, 3, true)).toBe(2);
  });

  it("brings a focus from outside to the first control, or with Shift the last", () => {
    expect(trapStep(-1, 3, false)).toBe(0);
    expect(trapStep(-1, 3, true)).toBe(2);
  });

  it("stays on a single control and finds none in an empty trap", () => {
    expect(trapStep(0, 1, false)).toBe(0);
    expect(trapStep(0, 1, true)).toBe(0);
    expect(trapStep(-1, 0, false)).toBe(-1);
  });
});

describe("focusAfterLeaving", () => {
  it("gives the focus to the clip that took the place of the one that left", () => {
    expect(focusAfterLeaving(1, 3)).toBe(1);
    expect(focusAfterLeaving(0, 1)).toBe(0);
  });

  it("falls back to the one before when the last clip left", () => {
    expect(focusAfterLeaving(2, 2)).toBe(1);
  });

  it("finds none when the group is empty", () => {
    expect(focusAfterLeaving(0, 0)).toBeNull();
  });
});
