/**
 * Where the compared groups came from, as a judgement records it (SPEC §8: source, time
 * taken, edits; docs/app.md, "Where a comparison comes from"). Pure.
 *
 * - `suggested`: the groups were loaded from a suggestion, edited or not. Moving, removing
 *   or adding single behaviours, adding a cluster with the modifier and taking a cluster
 *   back out are edits: each counts one and keeps the source.
 * - `explored`: the person filled a group from the chart, i.e. a click on a cluster put its
 *   behaviours in a group in place of the group's members, whatever was loaded before; and
 *   groups built up from empty.
 *
 * After each answer the page loads the next suggestion into the groups, so a comparison the
 * person builds in the chart right after an answer starts from a suggestion; the cluster
 * click that replaces a group's members is what makes it the person's own.
 */
import type { Suggestion } from "../api";
import type { ArcClick, Groups } from "./selection";

export type Source = "suggested" | "explored";

/** How the current groups came about. */
export interface Origin {
  source: Source;
  /** Group changes since the groups were last set as a whole (prefill, answer, undo). */
  edits: number;
  /** When the groups became non-empty (ms), for `seconds` of the judgement. */
  startedAt: number | null;
  /** The suggestion last loaded into the groups (passed over by "next suggestion"). */
  suggestion: Suggestion | null;
}

/** Empty groups: whatever the person puts in them is their own. */
export const FRESH_ORIGIN: Origin = { source: "explored", edits: 0, startedAt: null, suggestion: null };

/**
 * One change of the groups: `fill` puts a cluster's behaviours in a group in place of its
 * members; `edit` is any other change (move, remove, add, take out).
 */
export type GroupChange = "fill" | "edit";

/** What a click on an arc is: a cluster click without the modifier fills its target group;
 * the rest are edits. */
export function arcChange(click: ArcClick): GroupChange {
  return click.isLeaf || click.add ? "edit" : "fill";
}

/**
 * The origin after the groups changed to `after` by `change` at `at` (ms): one more edit,
 * the clock started if it was not, the source `explored` after a fill; empty groups start
 * afresh.
 */
export function originAfter(origin: Origin, change: GroupChange, after: Groups, at: number): Origin {
  if (after.A.length + after.B.length === 0) return FRESH_ORIGIN;
  return {
    ...origin,
    source: change === "fill" ? "explored" : origin.source,
    edits: origin.edits + 1,
    startedAt: origin.startedAt ?? at,
  };
}

/** The origin of groups loaded from a suggestion at `at` (ms). */
export function suggestedOrigin(suggestion: Suggestion, at: number): Origin {
  return { source: "suggested", edits: 0, startedAt: at, suggestion };
}
