import { describe, expect, it } from "vitest";
import { keyCommand } from "../src/lib/keys";

describe("keyCommand", () => {
  it("maps arrows and the left-hand keys to answers", () => {
    for (const [key, label] of [
      ["ArrowLeft", "left"],
      ["a", "left"],
      ["ArrowRight", "right"],
      ["D", "right"],
      ["ArrowUp", "equal"],
      ["w", "equal"],
    ] as const) {
      expect(keyCommand({ key }, "groupwise")).toEqual({ type: "answer", label });
    }
  });

  it("never answers on auto-repeat or in a form field", () => {
    expect(keyCommand({ key: "ArrowLeft", repeat: true }, "groupwise")).toBeNull();
    expect(keyCommand({ key: "a", inField: true }, "groupwise")).toBeNull();
  });

  it("answers with arrows wherever focus is, and leaves Shift + arrows to the chart", () => {
    expect(keyCommand({ key: "ArrowLeft" }, "groupwise")).toEqual({ type: "answer", label: "left" });
    expect(keyCommand({ key: "ArrowLeft", shiftKey: true }, "groupwise")).toBeNull();
    expect(keyCommand({ key: "ArrowUp", shiftKey: true }, "pairwise")).toBeNull();
    expect(keyCommand({ key: "A", shiftKey: true }, "groupwise")).toEqual({ type: "answer", label: "left" });
  });

  it("opens the guide with ? in both modes", () => {
    expect(keyCommand({ key: "?", shiftKey: true }, "groupwise")).toEqual({ type: "guide" });
    expect(keyCommand({ key: "?", shiftKey: true }, "pairwise")).toEqual({ type: "guide" });
  });

  it("has the group keys in groupwise mode and skip in pairwise mode", () => {
    expect(keyCommand({ key: "g" }, "groupwise")).toEqual({ type: "switch-group" });
    expect(keyCommand({ key: "2" }, "groupwise")).toEqual({ type: "target", group: "B" });
    expect(keyCommand({ key: "n" }, "groupwise")).toEqual({ type: "next-suggestion" });
    expect(keyCommand({ key: "ArrowDown" }, "groupwise")).toBeNull();
    expect(keyCommand({ key: "ArrowDown" }, "pairwise")).toEqual({ type: "skip" });
    expect(keyCommand({ key: "s" }, "pairwise")).toEqual({ type: "skip" });
    expect(keyCommand({ key: "g" }, "pairwise")).toBeNull();
  });

  it("undoes with U or Ctrl/Cmd+Z, and ignores other modified keys", () => {
    expect(keyCommand({ key: "u" }, "groupwise")).toEqual({ type: "undo" });
    expect(keyCommand({ key: "z", ctrlKey: true }, "pairwise")).toEqual({ type: "undo" });
    expect(keyCommand({ key: "z", metaKey: true }, "groupwise")).toEqual({ type: "undo" });
    expect(keyCommand({ key: "a", ctrlKey: true }, "groupwise")).toBeNull();
    expect(keyCommand({ key: "ArrowLeft", altKey: true }, "groupwise")).toBeNull();
  });
});

describe("the chart's centre by key", () => {
  it("Escape takes the chart one step out (groupwise only), not in a field", () => {
    expect(keyCommand({ key: "Escape" }, "groupwise")).toEqual({ type: "out" });
    expect(keyCommand({ key: "Escape", inField: true }, "groupwise")).toBeNull();
    expect(keyCommand({ key: "Escape" }, "pairwise")).toBeNull();
  });

  it("leaves C and Shift + arrows to the chart", () => {
    expect(keyCommand({ key: "c" }, "groupwise")).toBeNull();
    expect(keyCommand({ key: "ArrowUp", shiftKey: true }, "groupwise")).toBeNull();
  });
});
