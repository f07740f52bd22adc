/**
 * Which session the page shows: the one in the URL, the newest, or the start screen; opening
 * one (its state, the page's settings of it, event stream, round and agent); and the
 * New-session form's checks and creation, with a refusal put beside the env or above the
 * settings.
 */
import { ApiError, type SessionCreate, type SessionState, STALE } from "../api";
import type { NewSessionState } from "../state";
import type { EffectContext } from "./context";
import type { EventStream } from "./events";
import type { PageSettingsEffects } from "./page-settings";
import type { RoundSync } from "./round";

export function createSessions(
  { store, api, fail }: EffectContext,
  events: EventStream,
  round: RoundSync,
  setUrl: (sid: string | null) => void,
  pageSettings: PageSettingsEffects,
) {
  const dispatch = store.dispatch;

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
    events.close();
    setUrl(null);
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
    events.close();
    round.forget();
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
    setUrl(sid);
    dispatch({ type: "session", session, at: Date.now() });
    pageSettings.restore(sid);
    dispatch({ type: "boot", boot: "ready" });
    events.connect(sid);
    void round.syncAgent();
    await round.sync();
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

  return { boot, showStart, open, create, checkNewSession };
}
