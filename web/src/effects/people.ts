/**
 * A shared session (issue 21): the owner adds and removes people (each gets a link with a
 * token of their own, shown once), and an answer someone else gave takes its suggestion or
 * pair off this page, which shows the next one. While a shared round runs on a visible page
 * the people are read again every `REFRESH_MS`: each one's time shown grows with the clock,
 * and the event stream sends a state only when something else changed.
 */
import { type JudgementOut, STALE } from "../api";
import { afterAnswerElsewhere, isShared, judgementAnnotator, meOf } from "../lib/annotators";
import type { EffectContext } from "./context";
import type { GroupEffects } from "./groups";
import type { PairwiseFlow } from "./pairwise-flow";

export const REFRESH_MS = 10_000;

export function createPeople(
  { store, api, fail }: EffectContext,
  groups: GroupEffects,
  pairwise: PairwiseFlow,
  visible: () => boolean,
) {
  const dispatch = store.dispatch;
  const get = store.getState;
  let ticking: ReturnType<typeof setInterval> | null = null;

  /** Reads the people and their counters again (the owner's dialog, after a change);
   * `quiet`: a failure is not worth a message (the periodic read). */
  async function refresh(quiet = false): Promise<void> {
    const sid = get().session?.id;
    if (!sid) return;
    try {
      const list = await api.annotators(sid);
      if (list !== STALE) dispatch({ type: "annotators", sid, list });
    } catch (err) {
      if (!quiet) fail(err);
    }
  }

  /** Reads the people again every REFRESH_MS while a shared round runs on screen. */
  function keepTime(): void {
    const s = get().session;
    const running = !!s && isShared(s) && s.phase === "ready" && s.timer.running;
    if (running && !ticking) {
      ticking = setInterval(() => {
        const now = get().session;
        if (now && isShared(now) && now.timer.running && visible()) void refresh(true);
      }, REFRESH_MS);
    } else if (!running && ticking) {
      clearInterval(ticking);
      ticking = null;
    }
  }

  async function add(name: string): Promise<boolean> {
    const sid = get().session?.id;
    const clean = name.trim();
    if (!sid || get().people.busy) return false;
    if (!clean) {
      dispatch({ type: "people", patch: { error: "Type the person's name first." } });
      return false;
    }
    dispatch({ type: "people", patch: { busy: true, error: null, created: null } });
    try {
      const created = await api.addAnnotator(sid, clean);
      dispatch({ type: "people", patch: { busy: false, created } });
      await refresh();
      return true;
    } catch (err) {
      dispatch({ type: "people", patch: { busy: false, error: err instanceof Error ? err.message : String(err) } });
      return false;
    }
  }

  async function remove(aid: string): Promise<void> {
    const sid = get().session?.id;
    if (!sid || get().people.busy) return;
    dispatch({ type: "people", patch: { busy: true, error: null } });
    try {
      await api.removeAnnotator(sid, aid);
      const created = get().people.created;
      dispatch({ type: "people", patch: { busy: false, created: created?.id === aid ? null : created } });
      await refresh();
    } catch (err) {
      dispatch({ type: "people", patch: { busy: false, error: err instanceof Error ? err.message : String(err) } });
    }
  }

  /** Someone else's judgement arrived: what was on this page for the same question goes. */
  async function answeredElsewhere(j: JudgementOut): Promise<void> {
    const st = get();
    const s = st.session;
    const me = meOf(s);
    if (!s || s.phase !== "ready" || j.undone || j.round !== s.round) return;
    const who = judgementAnnotator(j);
    if (who.id === me.id) return;
    if (s.mode === "pairwise") {
      if (pairwise.dropAnswered(j)) {
        dispatch({ type: "toast", kind: "info", text: `${who.name} answered the pair you had; here is the next one.` });
      }
      return;
    }
    const what = afterAnswerElsewhere(st.groups, st.origin, j, me.id);
    if (what === "replace") {
      dispatch({ type: "clear" });
      dispatch({ type: "toast", kind: "info", text: `${who.name} answered the suggestion you had; here is the next one.` });
      await groups.suggest(true);
    } else if (what === "keep") {
      dispatch({
        type: "toast",
        kind: "info",
        text: `${who.name} already answered the suggestion you are editing; your groups stay as they are.`,
      });
    }
  }

  // Once the session is shared, the server leases what it offers to one person at a time;
  // what this page was offered before is asked for again so that it is leased to it too.
  store.subscribe((state, previous) => {
    if (state.session !== previous.session) keepTime();
    const s = state.session;
    if (!s || s.id !== previous.session?.id || !isShared(s) || isShared(previous.session)) return;
    if (s.mode === "pairwise") pairwise.reclaim();
    else void groups.reclaim();
  });

  return { refresh, add, remove, answeredElsewhere };
}

export type PeopleEffects = ReturnType<typeof createPeople>;
