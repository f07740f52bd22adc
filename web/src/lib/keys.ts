/**
 * Keyboard map (SPEC §9): ← left better, → right better, ↑ equal, ↓ skip (pairwise), with the
 * left-hand alternatives A / D / W / S; G switches the group that clicks fill (1 / 2 pick
 * A / B), N asks for the next suggestion, U or Ctrl+Z undoes the last answer, ? shows the
 * guide, Escape takes the chart one step out of the cluster it is centred on.
 *
 * The answer keys act wherever focus is on the page except in form fields, the chart
 * included: the chart's own keyboard navigation uses Shift + arrows (and Home / End), so it
 * never collides with answering. Auto-repeat never answers twice.
 */
import type { GroupId } from "./selection";

export type KeyCommand =
  | { type: "answer"; label: "left" | "right" | "equal" }
  | { type: "skip" }
  | { type: "switch-group" }
  | { type: "target"; group: GroupId }
  | { type: "next-suggestion" }
  | { type: "undo" }
  | { type: "guide" }
  | { type: "out" };

export interface KeyInput {
  key: string;
  ctrlKey?: boolean;
  metaKey?: boolean;
  altKey?: boolean;
  shiftKey?: boolean;
  repeat?: boolean;
  /** The event target is a text field, select or other form input. */
  inField?: boolean;
}

const ANSWERS: Record<string, "left" | "right" | "equal"> = {
  ArrowLeft: "left",
  a: "left",
  ArrowRight: "right",
  d: "right",
  ArrowUp: "equal",
  w: "equal",
};

export function keyCommand(e: KeyInput, mode: "groupwise" | "pairwise"): KeyCommand | null {
  if (e.inField) return null;
  const key = e.key.length === 1 ? e.key.toLowerCase() : e.key;
  if (e.ctrlKey || e.metaKey) return key === "z" && !e.altKey && !e.repeat ? { type: "undo" } : null;
  if (e.altKey) return null;
  if (e.shiftKey && key.startsWith("Arrow")) return null; // the chart's navigation
  if (e.repeat) return null;
  const label = ANSWERS[key];
  if (label) return { type: "answer", label };
  if (key === "?") return { type: "guide" };
  if (mode === "pairwise") {
    if (key === "ArrowDown" || key === "s") return { type: "skip" };
    if (key === "u") return { type: "undo" };
    return null;
  }
  switch (key) {
    case "g":
      return { type: "switch-group" };
    case "1":
      return { type: "target", group: "A" };
    case "2":
      return { type: "target", group: "B" };
    case "n":
      return { type: "next-suggestion" };
    case "u":
      return { type: "undo" };
    case "Escape":
      return { type: "out" };
    default:
      return null;
  }
}
