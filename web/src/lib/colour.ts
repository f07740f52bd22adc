/**
 * Colours of the views and the mixing of group tints.
 *
 * Groups use two Okabe–Ito colours that stay apart under the common colour-vision
 * deficiencies (orange and bluish green), and a second cue that needs no colour at all
 * (letters everywhere, a hatch on group B's leaves). Blue → red is kept for the history
 * edges (preferred → other end, SPEC §9) and so is not used for a group.
 */
import { rgb } from "d3-color";

export const GROUP_COLOURS = { A: "#E69F00", B: "#009E73" } as const;
export const NEUTRAL_LEAF = "#cfd5dd";
/** Neutral fill of the ring at each level above the leaves (lighter outwards). */
export const NEUTRAL_RINGS = ["#cfd5dd", "#dbe0e6", "#e4e8ec", "#ebeef1", "#f0f2f4"];
export const PREFERRED = "#0072B2";
export const OTHER = "#D55E00";
export const EQUAL = "#8E44AD";
export const SUGGESTION = "#6b7280";

export function neutralFill(level: number): string {
  return NEUTRAL_RINGS[Math.min(level, NEUTRAL_RINGS.length - 1)]!;
}

/** Weighted mean of colours in sRGB; weights need not sum to 1 (they are normalised). */
export function mix(parts: ReadonlyArray<readonly [string, number]>): string {
  let r = 0;
  let g = 0;
  let b = 0;
  let total = 0;
  for (const [colour, weight] of parts) {
    if (weight <= 0) continue;
    const c = rgb(colour);
    r += c.r * weight;
    g += c.g * weight;
    b += c.b * weight;
    total += weight;
  }
  if (total === 0) return rgb(parts[0]?.[0] ?? "#000").formatHex();
  return rgb(r / total, g / total, b / total).formatHex();
}

/**
 * The fill of an arc with `inA` and `inB` of its `size` leaves selected: the neutral colour
 * tinted towards each group's colour in proportion to its share of the leaves.
 */
export function groupTint(neutral: string, inA: number, inB: number, size: number): string {
  if (size <= 0 || (inA === 0 && inB === 0)) return rgb(neutral).formatHex();
  const fa = inA / size;
  const fb = inB / size;
  return mix([
    [neutral, Math.max(0, 1 - fa - fb)],
    [GROUP_COLOURS.A, fa],
    [GROUP_COLOURS.B, fb],
  ]);
}

/** rgba() of a hex colour with an alpha, for canvas strokes. */
export function withAlpha(colour: string, alpha: number): string {
  const c = rgb(colour);
  c.opacity = alpha;
  return c.formatRgb();
}

/** Opacity of a suggestion edge from its score in (0, 1]. */
export function suggestionAlpha(score: number): number {
  const s = Math.min(1, Math.max(0, score));
  return 0.12 + 0.55 * s;
}
