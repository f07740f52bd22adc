/**
 * A shared session (issue 21): the owner adds and removes people (each gets a link with a
 * token of their own, shown once), and an answer someone else gave takes its suggestion or
 * pair off this page, which shows the next one.
 */
import { type JudgementOut, STALE } from "../api";
import { afterAnswerElsewhere, isShared, judgementAnnotator, meOf } from "../lib/annotators";
import type { EffectContext } from "./context";
import type { GroupEffects } from "./groups";
import type { PairwiseFlow } from "./pairwise-flow";

export function createPeople({ store, api, fail }: EffectContext, groups: GroupEffects, pairwise: PairwiseFlow) {
  const dispatch = store.dispatch;
  const get = store.getState;

  /** Reads the people and their counters again (the owner's dialog, after a change). */
  async function refresh(): Promise<void> {
    const sid = get().session?.id;
    if (!sid) return;
    try {
      const list = await api.annotators(sid);
      if (list !== STALE) dispatch({ type: "annotators", sid, list });
    } catch (err) {
      fail(err);
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
    const s = state.session;
    if (!s || s.id !== previous.session?.id || !isShared(s) || isShared(previous.session)) return;
    if (s.mode === "pairwise") pairwise.reclaim();
    else void groups.reclaim();
  });

  return { refresh, add, remove, answeredElsewhere };
}

export type PeopleEffects = ReturnType<typeof createPeople>;
