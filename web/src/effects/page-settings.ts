/**
 * The page's settings of a session (playback speed, the group clicks fill): kept in session
 * storage as the groups are, so a reload keeps them, and restored when the session opens.
 */
import { pageSettingsKey, parsePageSettings } from "../lib/page-settings";
import type { State } from "../state";
import type { EffectContext } from "./context";

type Storage_ = Pick<Storage, "getItem" | "setItem">;

export function createPageSettings({ store }: EffectContext, storage: Storage_ | null) {
  /** Puts the session's stored settings in the store (those it has). */
  function restore(sid: string): void {
    if (!storage) return;
    let saved;
    try {
      saved = parsePageSettings(storage.getItem(pageSettingsKey(sid)));
    } catch {
      return; // storage disabled
    }
    if (saved.speed !== undefined) store.dispatch({ type: "view", patch: { speed: saved.speed } });
    if (saved.target !== undefined) store.dispatch({ type: "target", group: saved.target });
  }

  function save(state: State, previous: State): void {
    const sid = state.session?.id;
    if (!sid || !storage) return;
    if (state.view.speed === previous.view.speed && state.target === previous.target) return;
    try {
      storage.setItem(pageSettingsKey(sid), JSON.stringify({ speed: state.view.speed, target: state.target }));
    } catch {
      // Storage full or disabled: the settings just do not survive a reload.
    }
  }

  store.subscribe(save);
  return { restore };
}

export type PageSettingsEffects = ReturnType<typeof createPageSettings>;
