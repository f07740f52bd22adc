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
    success: "≥ 1 backward turn",
    description: "net backward turns of the torso",
  },
};

describe("env choice", () => {
  it("names a target with when an episode succeeds, in words", () => {
    expect(envOptionText(hopper)).toBe("Hopper");
    expect(envOptionText(backflip)).toBe("Hopper-backflip · success: ≥ 1 backward turn");
    const splits: EnvInfo = {
      ...backflip,
      name: "Walker2d-splits",
      target: { ...backflip.target!, unit: "s held", success: "a split held ≥ 1 s" },
    };
    expect(envOptionText(splits)).toBe("Walker2d-splits · success: a split held ≥ 1 s");
    expect(envOptionText(splits)).not.toContain("s held");
  });

  it("says in a line what the chosen env is", () => {
    expect(envAbout(hopper)).toBe("groupwise/Hopper-v0 · 1000 steps an episode · Falling (unhealthy) does not terminate.");
    expect(envAbout(backflip)).toBe(
      "Reward-free Hopper, scored by its target (backward turns); success: ≥ 1 backward turn, stretch: 2. " +
        "Net backward turns of the torso.",
    );
    expect(envAbout(null)).toContain("registered Gymnasium id");
  });
});
