import { describe, expect, it } from "vitest";
import { clipCaption, seconds } from "../src/lib/clip-timing";

describe("clip timing", () => {
  it("says how long a clip lasts", () => {
    expect(seconds(1.504)).toBe("1.5 s"); // Hopper: 188 steps of 0.008 s
    expect(seconds(0.24)).toBe("0.24 s");
    expect(seconds(2)).toBe("2 s");
  });

  it("says how fast it plays at the page's rate", () => {
    const hopper = { seconds: 1.504, speed: 1 };
    expect(clipCaption(hopper)).toBe("1.5 s · real speed");
    expect(clipCaption(hopper, 0.5)).toBe("1.5 s · 0.5× real speed");
    expect(clipCaption(hopper, 2)).toBe("1.5 s · 2× real speed");
    expect(clipCaption(null)).toBe("");
  });
});
