/**
 * The groups of the open groupwise round before they are answered: kept in session storage
 * (a reload restores them) and pre-filled or replaced by the server's suggestions.
 */
import { STALE } from "../api";
import { suggestedOrigin } from "../lib/origin";
import { fromSuggestion } from "../lib/selection";
import type { Origin, State } from "../state";
import type { EffectContext } from "./context";

type Storage_ = Pick<Storage, "getItem" | "setItem">;

export function createGroups({ store, api, fail }: EffectContext, storage: Storage_ | null) {
  const dispatch = store.dispatch;
  const get = store.getState;
  /** Suggestions of this round the person passed over with "next suggestion". */
  let passed: Array<[string[], string[]]> = [];

  const storageKey = () => {
    const r = get().round;
    return r ? `groupwise:groups:${r.sid}:${r.round}` : null;
  };

  /** Keeps the current groups in session storage (a reload restores them). */
  function save(state: State, previous: State): void {
    if (state.groups === previous.groups && state.origin === previous.origin) return;
    const key = storageKey();
    if (!key || !storage) return;
    try {
      storage.setItem(key, JSON.stringify({ groups: state.groups, origin: state.origin }));
    } catch {
      // Storage full or disabled: the groups just do not survive a reload.
    }
  }

  function restore(): boolean {
    const key = storageKey();
    const round = get().round;
    if (!key || !storage || !round) return false;
    try {
      const saved = JSON.parse(storage.getItem(key) ?? "null") as {
        groups: { A: string[]; B: string[] };
        origin: Origin;
      } | null;
      if (!saved || saved.groups.A.length + saved.groups.B.length === 0) return false;
      const known = (ids: string[]) => ids.every((id) => round.tree.nodes.get(id)?.isLeaf);
      if (!known(saved.groups.A) || !known(saved.groups.B)) return false;
      dispatch({ type: "set-groups", groups: fromSuggestion(saved.groups.A, saved.groups.B), origin: saved.origin });
      return true;
    } catch {
      return false;
    }
  }

  /** A new round's data is in the store: its saved groups come back, else a suggestion. */
  async function startRound(): Promise<void> {
    passed = [];
    if (!restore()) await suggest(true);
  }

  /**
   * Asks for the next suggested group query. `auto`: only fills empty groups (SPEC §5: the
   * interface pre-fills a suggestion when the person has not chosen groups).
   */
  async function suggest(auto: boolean): Promise<void> {
    const st = get();
    const s = st.session;
    const round = st.round;
    if (!s || !round || s.phase !== "ready" || s.mode !== "groupwise") return;
    const empty = () => get().groups.A.length + get().groups.B.length === 0;
    if (auto && !empty()) return;
    const current = st.origin.suggestion;
    if (!auto && current) {
      const query: [string[], string[]] = [[...current.left], [...current.right]];
      passed = [...passed, query].slice(-100);
    }
    dispatch({ type: "suggestion-status", status: "loading" });
    try {
      const reply = await api.nextSuggestion(s.id, round.round, passed);
      if (reply === STALE) return;
      const sug = reply.suggestion;
      if (!sug) {
        dispatch({ type: "suggestion-status", status: "none" });
        if (!auto) dispatch({ type: "toast", kind: "info", text: "No more suggestions this round; choose groups in the chart." });
        return;
      }
      dispatch({ type: "suggestion-status", status: "idle" });
      if (auto && !empty()) return; // the person started choosing meanwhile
      dispatch({
        type: "set-groups",
        groups: fromSuggestion(sug.left, sug.right),
        origin: suggestedOrigin(sug, Date.now()),
      });
    } catch (err) {
      dispatch({ type: "suggestion-status", status: "idle" });
      fail(err);
    }
  }

  /**
   * The session became shared (docs/teams.md): the suggestion on screen was offered before
   * there was anyone to keep it from, so it is asked for again, which leases it to this
   * person; when someone else holds it by now, the next one takes its place (groups the
   * person already changed stay).
   */
  async function reclaim(): Promise<void> {
    const st = get();
    const s = st.session;
    const round = st.round;
    const shown = st.origin.suggestion;
    if (!s || !round || s.phase !== "ready" || s.mode !== "groupwise" || !shown) return;
    const untouched = () => {
      const o = get().origin;
      return o.suggestion === shown && o.source === "suggested" && o.edits === 0;
    };
    if (!untouched()) return;
    try {
      const reply = await api.nextSuggestion(s.id, round.round, passed);
      if (reply === STALE || !reply.suggestion || reply.suggestion.id === shown.id || !untouched()) return;
      const sug = reply.suggestion;
      dispatch({ type: "set-groups", groups: fromSuggestion(sug.left, sug.right), origin: suggestedOrigin(sug, Date.now()) });
    } catch (err) {
      fail(err);
    }
  }

  store.subscribe(save);

  return { startRound, suggest, reclaim };
}

export type GroupEffects = ReturnType<typeof createGroups>;
