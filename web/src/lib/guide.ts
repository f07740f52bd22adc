/**
 * Whether the guide was closed before in this browser, per mode (localStorage): the guide
 * opens by itself only until the person closes it once.
 */

export type GuideStorage = Pick<Storage, "getItem" | "setItem">;

export const guideKey = (mode: string): string => `groupwise:guide-seen:${mode}`;

/** True once the guide of `mode` was closed here; false without storage (then it shows). */
export function guideSeen(storage: GuideStorage | null, mode: string): boolean {
  try {
    return storage?.getItem(guideKey(mode)) === "1";
  } catch {
    return false; // storage disabled: show the guide
  }
}

export function rememberGuideSeen(storage: GuideStorage | null, mode: string): void {
  try {
    storage?.setItem(guideKey(mode), "1");
  } catch {
    // Storage full or disabled: the guide opens again next time.
  }
}
