/**
 * Effects: everything that reaches the server and feeds the answers into the store.
 * Views call these through their handlers; only `api.ts` below this layer does I/O.
 */
import {
  type Api,
  ApiError,
  type ContinueIn,
  type JudgementOut,
  type Label,
  type SessionCreate,
  type SessionState,
  STALE,
} from "./api";
import { fromSuggestion } from "./lib/selection";
import { buildTree } from "./lib/tree";
import { uuid } from "./lib/uuid";
import { createPairwiseFlow } from "./pairwise-flow";
import { FRESH_ORIGIN, type NewSessionState, type Origin, type State, type Store } from "./state";

export interface ControllerOptions {
  annotator?: string;
  /** Where the selected groups survive a reload (sessionStorage by default). */
  storage?: Pick<Storage, "getItem" | "setItem"> | null;
  /** Puts the session id in the address bar. */
  setUrl?(sid: string | null): void;
  /** Whether the page can be seen now (default: the document is not hidden). */
  visible?(): boolean;
}

export function createController(store: Store, api: Api, options: ControllerOptions = {}) {
  const dispatch = store.dispatch;
  const get = store.getState;
  const annotator = options.annotator ?? "";
  const storage = options.storage === undefined ? globalThis.sessionStorage ?? null : options.storage;
  let closeEvents: (() => void) | null = null;
  /** "sid:round" of the round whose data is loaded or loading. */
  let roundKey: string | null = null;
  /** Suggestions of this round the person passed over with "next suggestion". */
  let passed: Array<[string[], string[]]> = [];
  /** "sid:round" of the round whose data arrived (the views show it). */
  let loadedKey: string | null = null;
  /** "sid:round" of the round reported shown (or being reported). */
  let shownKey: string | null = null;
  const visible = options.visible ?? (() => globalThis.document?.visibilityState !== "hidden");

  function fail(err: unknown): void {
    const text = err instanceof Error ? err.message : String(err);
    dispatch({ type: "toast", kind: "error", text });
  }

  const pairwise = createPairwiseFlow(store, api, annotator, fail);

  /* ------------------------------------------------------------- session */

  /** Opens the URL's session, else the newest, else (or with `fresh`) the start screen. */
  async function boot(sidFromUrl: string | null, fresh = false): Promise<void> {
    try {
      if (fresh) return await showStart();
      if (sidFromUrl) return await open(sidFromUrl);
      const sessions = await api.sessions();
      dispatch({ type: "sessions", sessions });
      if (sessions[0]) return await open(sessions[0].id);
      await showStart();
    } catch (err) {
      dispatch({ type: "boot", boot: "error", error: (err as Error).message });
    }
  }

  async function showStart(): Promise<void> {
    closeEvents?.();
    closeEvents = null;
    options.setUrl?.(null);
    dispatch({ type: "boot", boot: "choose" });
    try {
      const [envs, sessions, schema] = await Promise.all([api.envs(), api.sessions(), api.openapi()]);
      dispatch({ type: "schemas", schemas: schema.components.schemas });
      dispatch({ type: "envs", envs });
      dispatch({ type: "sessions", sessions });
    } catch (err) {
      fail(err);
    }
  }

  async function open(sid: string): Promise<void> {
    closeEvents?.();
    roundKey = null;
    loadedKey = null;
    dispatch({ type: "boot", boot: "loading" });
    let session: SessionState | typeof STALE;
    try {
      session = await api.session(sid);
    } catch (err) {
      if (err instanceof ApiError && err.status === 404) {
        await showStart();
        dispatch({ type: "toast", kind: "error", text: `Session ${sid} does not exist; choose or start one.` });
        return;
      }
      throw err;
    }
    if (session === STALE) return;
    options.setUrl?.(sid);
    dispatch({ type: "session", session, at: Date.now() });
    dispatch({ type: "boot", boot: "ready" });
    connect(sid);
    void syncAgent();
    await syncRound();
  }

  async function create(body: SessionCreate): Promise<void> {
    dispatch({ type: "busy", value: true });
    let session: SessionState;
    try {
      session = await api.createSession(body);
    } catch (err) {
      const refusal = await whyRefused(body, err);
      if (refusal !== STALE) dispatch({ type: "new-session", patch: refusal });
      return;
    } finally {
      dispatch({ type: "busy", value: false });
    }
    dispatch({ type: "new-session", patch: { resolved: null, envError: null, error: null } });
    await open(session.id);
  }

  /** What the server would store for the New-session form's body, or why it would refuse. */
  async function checkNewSession(body: SessionCreate): Promise<void> {
    try {
      const resolved = await api.resolveSettings(body);
      if (resolved !== STALE) dispatch({ type: "new-session", patch: { resolved, envError: null, error: null } });
    } catch (err) {
      const refusal = await whyRefused(body, err);
      if (refusal !== STALE) dispatch({ type: "new-session", patch: refusal });
    }
  }

  /** A refusal (422) is the env's when the env alone is refused too, else the settings'. */
  async function whyRefused(body: SessionCreate, err: unknown): Promise<Partial<NewSessionState> | typeof STALE> {
    const message = err instanceof Error ? err.message : String(err);
    if (!(err instanceof ApiError) || err.status !== 422) return { error: message };
    if (Object.keys(body.settings ?? {}).length === 0) return { envError: message, error: null };
    try {
      const alone = await api.resolveSettings({ env: body.env, mode: body.mode });
      return alone === STALE ? STALE : { envError: null, error: message };
    } catch (again) {
      return { envError: again instanceof Error ? again.message : String(again), error: null };
    }
  }

  function connect(sid: string): void {
    dispatch({ type: "connection", value: "connecting" });
    let dropped = false;
    closeEvents = api.events(sid, {
      open() {
        dispatch({ type: "connection", value: "open" });
        // Events missed while the stream was down: read the state again.
        if (dropped) void resync(sid);
      },
      error() {
        dropped = true;
        dispatch({ type: "connection", value: "lost" });
      },
      state(session) {
        if (session.id !== get().session?.id) return;
        dispatch({ type: "session", session, at: Date.now() });
        void syncRound();
        void syncAgent();
        void reportShown();
      },
      judgement(j) {
        if (j.undone) dispatch({ type: "judgement-undone", id: j.id });
        else dispatch({ type: "judgement-stored", judgement: j });
      },
      round() {
        void resync(sid);
      },
    });
  }

  async function resync(sid: string): Promise<void> {
    try {
      const session = await api.session(sid);
      if (session === STALE || get().session?.id !== sid) return;
      dispatch({ type: "session", session, at: Date.now() });
      await syncRound();
    } catch (err) {
      fail(err);
    }
  }

  /** "sid:round" of the finished session whose agent is loaded or loading. */
  let agentKey: string | null = null;

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

  /** Loads the open round's data once the session has one (not while it is prepared). */
  async function syncRound(): Promise<void> {
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
    passed = [];
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
    if (!restoreGroups()) await suggest(true);
  }

  async function loadPairwiseRound(s: SessionState): Promise<void> {
    const judgements = await api.judgements(s.id, s.round);
    if (judgements === STALE) return;
    dispatch({ type: "judgements", judgements });
    await pairwise.start();
  }

  /**
   * Tells the server the open round is on screen, once per round: its timer starts then, so
   * a round that waited for the person uses none of its time (docs/app.md, "The round
   * timer"). On screen means its data arrived, the page is not hidden and the guide does not
   * cover it; the page calls this again when any of these changes.
   */
  async function reportShown(): Promise<void> {
    const st = get();
    const s = st.session;
    if (!s || st.boot !== "ready" || s.phase !== "ready" || s.timer.shown_at) return;
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

  /* ------------------------------------------------------------- groups */

  const storageKey = () => {
    const r = get().round;
    return r ? `groupwise:groups:${r.sid}:${r.round}` : null;
  };

  /** Keeps the current groups in session storage (a reload restores them). */
  function saveGroups(state: State, previous: State): void {
    if (state.groups === previous.groups && state.origin === previous.origin) return;
    const key = storageKey();
    if (!key || !storage) return;
    try {
      storage.setItem(key, JSON.stringify({ groups: state.groups, origin: state.origin }));
    } catch {
      // Storage full or disabled: the groups just do not survive a reload.
    }
  }

  function restoreGroups(): boolean {
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
        origin: { source: "suggested", edits: 0, startedAt: Date.now(), suggestion: sug },
      });
    } catch (err) {
      dispatch({ type: "suggestion-status", status: "idle" });
      fail(err);
    }
  }

  /* ------------------------------------------------------------- answers */

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
      await suggest(true);
    } catch (err) {
      dispatch({ type: "submitting", value: false });
      fail(err);
    }
  }

  function lastJudgement(): JudgementOut | null {
    const list = get().judgements;
    return list.length ? list[list.length - 1]! : null;
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
      fail(err);
    } finally {
      dispatch({ type: "undoing", value: false });
    }
  }

  /* ------------------------------------------------------------- controls */

  async function control(action: "pause" | "resume" | "end-round" | "retry"): Promise<void> {
    const s = get().session;
    if (!s || get().busy) return;
    dispatch({ type: "busy", value: true });
    try {
      const session = await api.control(s.id, action);
      dispatch({ type: "session", session, at: Date.now() });
      void syncRound();
    } catch (err) {
      fail(err);
    } finally {
      dispatch({ type: "busy", value: false });
    }
  }

  /** "Finish now" (no more rounds after this one) and "Continue training". */
  async function endSession(body: ContinueIn | null): Promise<void> {
    const s = get().session;
    if (!s || get().busy) return;
    dispatch({ type: "busy", value: true });
    try {
      const session = body ? await api.continueTraining(s.id, body) : await api.finish(s.id);
      dispatch({ type: "session", session, at: Date.now() });
      void syncRound();
    } catch (err) {
      fail(err);
    } finally {
      dispatch({ type: "busy", value: false });
    }
  }

  store.subscribe(saveGroups);

  return {
    boot,
    open,
    create,
    checkNewSession,
    showStart,
    suggest,
    answer,
    undo,
    reportShown,
    answerPair: pairwise.answer,
    skipPair: pairwise.skip,
    control,
    finish: () => endSession(null),
    continueTraining: (body: ContinueIn) => endSession(body),
    lastJudgement,
  };
}

export type Controller = ReturnType<typeof createController>;
