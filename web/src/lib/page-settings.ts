/**
 * The page's own settings of a session that a reload keeps (issue 23): the clips' playback
 * speed and the group plain clicks fill. Stored per session as JSON beside its groups
 * (`effects/page-settings.ts`); this module reads them back, keeping only valid values.
 */
import type { GroupId } from "./selection";

/** The playback rates the speed menus offer. */
export const SPEEDS: readonly number[] = [0.25, 0.5, 1, 1.5, 2];

export interface PageSettings {
  speed: number;
  target: GroupId;
}

export const pageSettingsKey = (sid: string): string => `groupwise:page:${sid}`;

/** The settings stored as `raw`: each one present and valid, the rest left out. */
export function parsePageSettings(raw: string | null): Partial<PageSettings> {
  let value: unknown;
  try {
    value = JSON.parse(raw ?? "null");
  } catch {
    return {};
  }
  if (typeof value !== "object" || value === null) return {};
  const { speed, target } = value as Record<string, unknown>;
  const out: Partial<PageSettings> = {};
  if (typeof speed === "number" && SPEEDS.includes(speed)) out.speed = speed;
  if (target === "A" || target === "B") out.target = target;
  return out;
}
