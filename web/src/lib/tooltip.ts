/** Where a floating box goes beside the pointer without leaving its area (pure). */

export interface Bounds {
  left: number;
  top: number;
  right: number;
  bottom: number;
}

function clamp(value: number, lo: number, hi: number): number {
  return Math.max(lo, Math.min(value, hi));
}

/**
 * The top-left corner of a `width` × `height` box for a pointer at (x, y): right of and below
 * the pointer by `offset`, else left of / above it, then clamped into `bounds` (to its
 * top-left corner when the box is larger than the bounds). The tooltip of the chart passes
 * the chart's area, so it never covers the controls around the chart.
 */
export function placeBeside(
  x: number,
  y: number,
  width: number,
  height: number,
  bounds: Bounds,
  offset = 18,
): { left: number; top: number } {
  let left = x + offset;
  if (left + width > bounds.right) left = x - offset - width;
  let top = y + offset;
  if (top + height > bounds.bottom) top = y - offset - height;
  return {
    left: clamp(left, bounds.left, bounds.right - width),
    top: clamp(top, bounds.top, bounds.bottom - height),
  };
}
