/**
 * Selection rules of the two groups (SPEC §9, paper "Interactive comparison of behaviour
 * groups"). Pure: each rule takes the groups and returns new ones, or the same ones and a
 * message saying why nothing changed.
 *
 * - Clicking a parent arc puts all its leaves into the target group, replacing it; with the
 *   modifier, adds them. A click that would change nothing (the cluster is the group
 *   already) says so and leaves the group as it is: it never empties it (issue 40). A
 *   cluster of more than MAX_GROUP leaves is refused here; the chart centres on it instead
 *   (`lib/centre.ts`).
 * - Clicking a leaf puts it into the target group (out of the other one); clicking a leaf
 *   already in the target group says so. Removing a leaf is its own gesture: the modifier
 *   click on a leaf in a group takes it out (as does the × on its clip).
 * - A behaviour is never in both groups: putting it in one takes it out of the other.
 * - A group holds at most MAX_GROUP behaviours (the server enforces it too).
 */

import limits from "../limits.json";

export type GroupId = "A" | "B";

export interface Groups {
  readonly A: readonly string[];
  readonly B: readonly string[];
}

/** The server's limit on a group (`groupwise.preferences.judgement.MAX_GROUP`), generated
 * into `limits.json` with the API contract and checked against the server by its tests. */
export const MAX_GROUP: number = limits.max_group;
export const EMPTY_GROUPS: Groups = { A: [], B: [] };

export interface SelectionResult {
  groups: Groups;
  changed: boolean;
  /** Why nothing changed, for the person. */
  message?: string;
}

export const otherGroup = (g: GroupId): GroupId => (g === "A" ? "B" : "A");

export function groupOf(groups: Groups, id: string): GroupId | null {
  if (groups.A.includes(id)) return "A";
  if (groups.B.includes(id)) return "B";
  return null;
}

function withGroup(groups: Groups, g: GroupId, ids: readonly string[]): Groups {
  return g === "A" ? { A: ids, B: groups.B } : { A: groups.A, B: ids };
}

function same(a: readonly string[], b: readonly string[]): boolean {
  return a.length === b.length && a.every((x, i) => x === b[i]);
}

function result(before: Groups, after: Groups, message?: string): SelectionResult {
  const changed = !same(before.A, after.A) || !same(before.B, after.B);
  return message ? { groups: before, changed: false, message } : { groups: after, changed };
}

function tooMany(g: GroupId, count: number): string {
  return `Group ${g} can hold at most ${MAX_GROUP} behaviours; this would make ${count}.`;
}

/** Puts `ids` into group `g` (replacing it, or appended when `add`), out of the other. */
export function assign(groups: Groups, g: GroupId, ids: readonly string[], add: boolean): SelectionResult {
  const incoming = new Set(ids);
  const current = new Set(groups[g]);
  const next = add ? [...groups[g], ...ids.filter((id) => !current.has(id))] : [...incoming];
  if (next.length > MAX_GROUP) return result(groups, groups, tooMany(g, next.length));
  const o = otherGroup(g);
  const other = groups[o].filter((id) => !incoming.has(id));
  return result(groups, withGroup(withGroup(groups, g, next), o, other));
}

/** Removes one behaviour from whichever group holds it. */
export function removeLeaf(groups: Groups, id: string): SelectionResult {
  return result(groups, { A: groups.A.filter((x) => x !== id), B: groups.B.filter((x) => x !== id) });
}

/** Moves one behaviour to the other group (appended). */
export function moveLeaf(groups: Groups, id: string): SelectionResult {
  const from = groupOf(groups, id);
  if (!from) return result(groups, groups);
  return assign(groups, otherGroup(from), [id], true);
}

export interface ArcClick {
  /** The clicked node (a click on a cluster too big for a group centres the chart on it). */
  id?: string;
  /** Leaves under the clicked arc (one for a leaf). */
  leaves: readonly string[];
  isLeaf: boolean;
  /** The group the click targets (the active one, or the other one). */
  target: GroupId;
  /** The modifier (Shift/Ctrl/Cmd): add instead of replace. */
  add: boolean;
}

/** The selection after clicking an arc. */
export function clickArc(groups: Groups, click: ArcClick): SelectionResult {
  const { leaves, target, add } = click;
  if (click.isLeaf) {
    const id = leaves[0];
    if (id === undefined) return result(groups, groups);
    const where = groupOf(groups, id);
    if (add && where !== null) return removeLeaf(groups, id);
    if (where === target) {
      return result(groups, groups, `${id} is in group ${target} already; Shift-click it or its × takes it out.`);
    }
    return assign(groups, target, [id], true);
  }
  if (leaves.length === 0) return result(groups, groups);
  const inTarget = new Set(groups[target]);
  if (leaves.every((id) => inTarget.has(id)) && (add || groups[target].length === leaves.length)) {
    const n = leaves.length;
    return result(groups, groups, `Group ${target} holds ${n === 1 ? "this behaviour" : `these ${n} behaviours`} already.`);
  }
  if (!add && leaves.length > MAX_GROUP) {
    return result(
      groups,
      groups,
      `This cluster has ${leaves.length} behaviours; a group holds at most ${MAX_GROUP}. ` +
        "Pick a smaller cluster or single behaviours.",
    );
  }
  return assign(groups, target, leaves, add);
}

/** Groups from a suggestion: left → A, right → B, cut to MAX_GROUP, disjoint. */
export function fromSuggestion(left: readonly string[], right: readonly string[]): Groups {
  const a = [...new Set(left)].slice(0, MAX_GROUP);
  const inA = new Set(a);
  const b = [...new Set(right)].filter((id) => !inA.has(id)).slice(0, MAX_GROUP);
  return { A: a, B: b };
}

/** Counts of each group's leaves under every node (for tints), from leaf -> ancestors. */
export function groupCounts(
  groups: Groups,
  ancestorsOf: (leaf: string) => readonly string[],
): Map<string, { A: number; B: number }> {
  const counts = new Map<string, { A: number; B: number }>();
  for (const g of ["A", "B"] as const) {
    for (const leaf of groups[g]) {
      for (const id of [leaf, ...ancestorsOf(leaf)]) {
        let c = counts.get(id);
        if (!c) counts.set(id, (c = { A: 0, B: 0 }));
        c[g] += 1;
      }
    }
  }
  return counts;
}
