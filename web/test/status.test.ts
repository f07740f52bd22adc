import { describe, expect, it } from "vitest";
import { roundsOver } from "../src/views/status";

describe("the status bar", () => {
  it("drops the round's timer, counters and End round once the rounds are over", () => {
    for (const phase of ["preparing", "ready", "training", "failed"] as const) expect(roundsOver({ phase })).toBe(false);
    for (const phase of ["finishing", "finished"] as const) expect(roundsOver({ phase })).toBe(true);
  });
});
