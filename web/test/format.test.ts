import { describe, expect, it } from "vitest";
import { clock, elapsedNow, phaseName, question, roundOf } from "../src/lib/format";
import { bestGrid } from "../src/lib/grid";

describe("format", () => {
  it("formats a clock", () => {
    expect(clock(0)).toBe("0:00");
    expect(clock(65.9)).toBe("1:05");
    expect(clock(3725)).toBe("1:02:05");
  });

  it("runs the round timer only while it runs", () => {
    expect(elapsedNow({ elapsed_s: 10, paused: false, running: true }, 2500)).toBe(12.5);
    expect(elapsedNow({ elapsed_s: 10, paused: true, running: false }, 2500)).toBe(10);
  });

  it("numbers rounds from 0, as the API, the export and the checkpoints do", () => {
    expect(roundOf(0, 5)).toBe("0 of 0–4");
    expect(roundOf(4, 5)).toBe("4 of 0–4");
    expect(roundOf(5, 5)).toBe("4 of 0–4"); // never past the last round
    expect(roundOf(0, 1)).toBe("0 (the only one)");
  });

  it("asks the same question in both modes", () => {
    expect(question("clip")).toBe("Which clip is closer to the behaviour you want?");
    expect(question("group")).toBe("Which group is closer to the behaviour you want?");
  });

  it("names worker phases for people", () => {
    expect(phaseName("ppo")).toBe("Training the agent (PPO)");
    expect(phaseName("reward")).toBe("Training the reward model");
    expect(phaseName("new_thing")).toBe("New thing");
  });
});

describe("bestGrid", () => {
  it("fits n square clips into the box as large as possible", () => {
    expect(bestGrid(1, 300, 200)).toEqual({ cols: 1, cell: 200 });
    expect(bestGrid(4, 300, 300)).toEqual({ cols: 2, cell: 146 });
    expect(bestGrid(3, 600, 200)).toEqual({ cols: 3, cell: 194 });
    expect(bestGrid(8, 330, 430)).toEqual({ cols: 3, cell: 104 });
  });
});
