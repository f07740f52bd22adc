import { describe, expect, it } from "vitest";
import { buildTree } from "../src/lib/tree";
import type { RoundData } from "../src/state";
import { previewContent } from "../src/views/preview";
import { FOUR } from "./fixtures";

const clip = { steps: 188, stride: 4, frames: 47, fps: 31.25, seconds: 1.504, speed: 1, step_seconds: 0.008 };
const round: RoundData = { sid: "s-1", round: 0, tree: buildTree(FOUR), medoids: { m1: ["b1"] }, clip };
const url = (c: string) => `/clips/${c}`;
const node = (id: string) => round.tree.nodes.get(id)!;

describe("the chart's preview", () => {
  it("says how long a leaf's clip is and how fast it plays, as the comparison does", () => {
    const leaf = previewContent(round, node("b2"), undefined, new Set(), url);
    expect(leaf.title).toBe("behaviour b2");
    expect(leaf.clips).toEqual([{ id: "b2", src: "/clips/c2.mp4" }]);
    expect(leaf.timing).toBe("1.5 s · real speed");
  });

  it("says it for a cluster's clips too, and nothing for a pool without a timing", () => {
    expect(previewContent(round, node("m1"), undefined, new Set(), url).timing).toBe("1.5 s · real speed");
    expect(previewContent({ ...round, clip: null }, node("b2"), undefined, new Set(), url).timing).toBe("");
  });
});
