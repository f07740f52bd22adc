/**
 * Where keyboard focus goes when the page moves it itself (issue 23): Tab inside an open
 * dialog, and after a clip leaves a group from its own button. Pure: indices in, index out.
 */

/**
 * The control Tab reaches in a focus trap of `count` controls in order, from the one at
 * `index` (-1: the focus is outside the trap): the next, or with Shift the previous,
 * wrapping around; -1 when there is none.
 */
export function trapStep(index: number, count: number, backwards: boolean): number {
  if (count <= 0) return -1;
  if (index < 0 || index >= count) return backwards ? count - 1 : 0;
  return (index + (backwards ? count - 1 : 1)) % count;
}

/**
 * The clip of a group that takes the focus after the clip at `index` left it and
 * `remaining` clips stay: the one now in its place, else the one before it; null when the
 * group is empty.
 */
export function focusAfterLeaving(index: number, remaining: number): number | null {
  if (remaining <= 0) return null;
  return Math.max(0, Math.min(index, remaining - 1));
}
