/**
 * The person's judgements: an answer on the two groups (sent once, with its source, edits
 * and time) and undo of the last judgement, which puts its groups, or in pairwise mode its
 * pair, back on screen. (Pairwise answers go through `pairwise-flow.ts`.)
 */
import { ApiError, type JudgementOut, type Label } from "../api";
import { meOf, undoTarget } from "../lib/annotators";
import { fromSuggestion } from "../lib/selection";
import { uuid } from "../lib/uuid";
import { FRESH_ORIGIN } from "../state";
import type { EffectContext } from "./context";
import type { GroupEffects } from "./groups";
import type { PairwiseFlow } from "./pairwise-flow";

export function createAnswers(
  { store, api, fail }: EffectContext,
  annotator: string,
  groups: GroupEffects,
  pairwise: PairwiseFlow,
) {
  const dispatch = store.dispatch;
  const get = store.getState;

  async function answer(label: Label): Promise<void> {
    const st = get();
    const s = st.session;
    const round = st.round;
    const { A, B } = st.groups;
    if (st.submitting || !s || !round) return;
    const why =
      s.phase !== "ready"
        ? "No answer saved: the round is not open."
        : !A.length || !B.length
          ? `No answer saved: group ${A.length ? "B" : "A"} is empty. Click arcs to fill it ` +
            "(Alt-click fills the other group), or press N for a suggestion."
          : null;
    if (why) {
      dispatch({ type: "toast", kind: "info", text: why });
      return;
    }
    dispatch({ type: "submitting", value: true });
    const started = st.origin.startedAt ?? Date.now();
    try {
      const j = await api.submitJudgement(s.id, {
        client_id: uuid(),
        round: round.round,
        left: [...A],
        right: [...B],
        label,
        source: st.origin.source,
        seconds: Math.max(0, (Date.now() - started) / 1000),
        edits: st.origin.edits,
        annotator,
      });
      dispatch({ type: "answered", judgement: j });
      await groups.suggest(true);
    } catch (err) {
      dispatch({ type: "submitting", value: false });
      fail(err);
    }
  }

  /** The judgement undo takes back: this person's last of the round (`undoTarget`). */
  function lastJudgement(): JudgementOut | null {
    const st = get();
    return undoTarget(st.judgements, meOf(st.session).id);
  }

  async function undo(): Promise<void> {
    const st = get();
    const s = st.session;
    const j = lastJudgement();
    if (!s || !j || st.undoing || s.phase !== "ready") return;
    dispatch({ type: "undoing", value: true });
    try {
      await api.undoJudgement(s.id, j.id);
      dispatch({ type: "judgement-undone", id: j.id });
      if (s.mode === "pairwise") pairwise.restore(j.id);
      else {
        dispatch({
          type: "set-groups",
          groups: fromSuggestion(j.left, j.right),
          origin: {
            ...FRESH_ORIGIN,
            source: j.source === "suggested" ? "suggested" : "explored",
            edits: j.edits,
            startedAt: Date.now() - j.seconds * 1000,
          },
        });
      }
      dispatch({ type: "toast", kind: "info", text: "Last answer undone." });
    } catch (err) {
      // Another person's judgement (shared sessions): the server says whose, and it stays.
      if (err instanceof ApiError && err.status === 403) {
        dispatch({ type: "toast", kind: "error", text: `Not undone: ${err.message}` });
      } else fail(err);
    } finally {
      dispatch({ type: "undoing", value: false });
    }
  }

  return { answer, undo, lastJudgement };
}
