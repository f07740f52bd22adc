import { describe, expect, it } from "vitest";
import { failedTitle } from "../src/views/progress";

describe("the heading of a failed session", () => {
  it("says which step failed (issue 23: it said the worker stopped when the worker went on)", () => {
    expect(failedTitle("preparing", 0, 5)).toBe("Round 0 of 0–4 could not be prepared");
    expect(failedTitle("training", 2, 5)).toBe("Training after round 2 failed");
    expect(failedTitle("finishing", 4, 5)).toBe("The final training failed");
  });

  it("falls back to the worker when no step is known", () => {
    expect(failedTitle(null, 0, 5)).toBe("The training worker stopped");
  });
});
