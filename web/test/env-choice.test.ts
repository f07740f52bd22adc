import { describe, expect, it } from "vitest";
import type { EnvInfo } from "../src/api";
import { envAbout, envOptionText } from "../src/lib/env-choice";

const hopper: EnvInfo = {
  name: "Hopper",
  gym_id: "groupwise/Hopper-v0",
  kind: "env",
  horizon: 1000,
  clip_seconds: 1.5,
  description: "falling (unhealthy) does not terminate",
  target: null,
};
const backflip: EnvInfo = {
  ...hopper,
  name: "Hopper-backflip",
  gym_id: "groupwise/Hopper-backflip-v0",
  kind: "target",
  target: {
    name: "hopper-backflip",
    base: "Hopper",
    unit: "backward turns",
    threshold: 1,
    stretch: 2,
    description: "net backward turns of the torso",
  },
};

describe("env choice", () => {
  it("names a target with what it scores and when it succeeds", () => {
    expect(envOptionText(hopper)).toBe("Hopper");
    expect(envOptionText(backflip)).toBe("Hopper-backflip · backward turns ≥ 1");
    expect(envOptionText({ ...backflip, target: { ...backflip.target!, threshold: 0.333333 } })).toBe(
      "Hopper-backflip · backward turns ≥ 0.333",
    );
  });

  it("says in a line what the chosen env is", () => {
    expect(envAbout(hopper)).toBe("groupwise/Hopper-v0 · 1000 steps an episode · Falling (unhealthy) does not terminate.");
    expect(envAbout(backflip)).toBe(
      "Reward-free Hopper, scored by its target: backward turns; an episode succeeds at 1 (stretch 2). " +
        "Net backward turns of the torso.",
    );
    expect(envAbout(null)).toContain("registered Gymnasium id");
  });
});
