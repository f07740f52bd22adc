/**
 * The session's current round on the page: its data loaded once per round (the tree,
 * suggestion edges and judgements, or the pairwise queue), the finished session's agent once
 * per round, and the report that the open round is on screen (its timer starts then).
 * Rounds are named "sid:round"; a load for a round the session moved past is dropped.
 */
import { ApiError, type SessionState, STALE } from "../api";
import { isShared } from "../lib/annotators";
import { buildTree } from "../lib/tree";
import type { EffectContext } from "./context";
import type { GroupEffects } from "./groups";
import type { PairwiseFlow } from "./pairwise-flow";

export function createRoundSync(
  { store, api, fail }: EffectContext,
  groups: GroupEffects,
  pairwise: PairwiseFlow,
  visible: () => boolean,
) {
  const dispatch = store.dispatch;
  const get = store.getState;
  /** The round whose data is loaded or loading. */
  let roundKey: string | null = null;
  /** The round whose data arrived (the views show it). */
  let loadedKey: string | null = null;
  /** The round reported shown (or being reported). */
  let shownKey: string | null = null;
  /** The finished session's round whose agent is loaded or loading. */
  let agentKey: string | null = null;

  /** Another session is being opened: whatever round is loaded is not its. */
  function forget(): void {
    roundKey = null;
    loadedKey = null;
  }

  /** Loads the open round's data once the session has one (not while it is prepared). */
  async function sync(): Promise<void> {
    const s = get().session;
    if (!s || s.phase === "preparing") return;
    const key = `${s.id}:${s.round}`;
    if (key === roundKey) return;
    roundKey = key;
    try {
      if (s.mode === "pairwise") await loadPairwiseRound(s);
      else await loadGroupRound(s);
      if (roundKey === key) loadedKey = key;
      void reportShown();
    } catch (err) {
      if (roundKey === key) roundKey = null;
      // A closed round's data may be gone; only an open round's failure needs a message.
      if (get().session?.phase === "ready") fail(err);
    }
  }

  async function loadGroupRound(s: SessionState): Promise<void> {
    const [tree, edges, judgements] = await Promise.all([
      api.tree(s.id, s.round),
      api.edges(s.id, s.round, Math.max(1, s.settings.suggestions)),
      api.judgements(s.id, s.round),
    ]);
    if (tree === STALE || edges === STALE || judgements === STALE) return;
    dispatch({
      type: "round-data",
      round: {
        sid: s.id,
        round: tree.round,
        tree: buildTree(tree.tree, tree.levels),
        medoids: tree.medoids,
        clip: tree.clip ?? null,
      },
    });
    dispatch({ type: "suggestions", edges });
    dispatch({ type: "judgements", judgements });
    await groups.startRound();
  }

  async function loadPairwiseRound(s: SessionState): Promise<void> {
    const judgements = await api.judgements(s.id, s.round);
    if (judgements === STALE) return;
    dispatch({ type: "judgements", judgements });
    await pairwise.start();
  }

  /** Loads the finished session's agent (summary, for its video and chart) once per round. */
  async function syncAgent(): Promise<void> {
    const s = get().session;
    if (!s || s.phase !== "finished") return;
    const key = `${s.id}:${s.round}`;
    if (key === agentKey) return;
    agentKey = key;
    try {
      const agent = await api.agent(s.id);
      if (agent === STALE || agentKey !== key) return;
      dispatch({ type: "agent", key, agent });
    } catch (err) {
      if (agentKey !== key) return;
      if (err instanceof ApiError && err.status === 404) dispatch({ type: "agent", key, agent: null });
      else {
        agentKey = null;
        fail(err);
      }
    }
  }

  /**
   * Tells the server the open round is on screen, once per round: its timer starts then, so
   * a round that waited for the person uses none of its time (docs/app.md, "The round
   * timer"); in a shared session each page reports, for its person's time shown. On screen
   * means its data arrived, the page is not hidden and the guide does not
   * cover it; the page calls this again when any of these changes.
   */
  async function reportShown(): Promise<void> {
    const st = get();
    const s = st.session;
    // In a shared session every page reports too: each person's time shown starts then.
    if (!s || st.boot !== "ready" || s.phase !== "ready" || (s.timer.shown_at && !isShared(s))) return;
    const key = `${s.id}:${s.round}`;
    if (loadedKey !== key || shownKey === key || st.guide || !visible()) return;
    shownKey = key;
    try {
      const session = await api.shown(s.id, s.round);
      if (get().session?.id === session.id) dispatch({ type: "session", session, at: Date.now() });
    } catch (err) {
      // The round closed meanwhile (409): nothing to start. Otherwise try again next time.
      if (!(err instanceof ApiError && err.status === 409) && shownKey === key) shownKey = null;
    }
  }

  return { forget, sync, syncAgent, reportShown };
}

export type RoundSync = ReturnType<typeof createRoundSync>;
