/**
 * The session's controls: pause, resume, end the round, retry after a failure, finish now,
 * continue training. Each reply is the new state; one control at a time (`busy`).
 */
import type { ContinueIn, SessionState } from "../api";
import type { EffectContext } from "./context";
import type { RoundSync } from "./round";

export type Control = "pause" | "resume" | "end-round" | "retry";

export function createControls({ store, api, fail }: EffectContext, round: RoundSync) {
  const dispatch = store.dispatch;
  const get = store.getState;

  /** Sends `request` for the open session unless a control is in flight; stores the reply. */
  async function send(request: (sid: string) => Promise<SessionState>): Promise<void> {
    const s = get().session;
    if (!s || get().busy) return;
    dispatch({ type: "busy", value: true });
    try {
      const session = await request(s.id);
      dispatch({ type: "session", session, at: Date.now() });
      void round.sync();
    } catch (err) {
      fail(err);
    } finally {
      dispatch({ type: "busy", value: false });
    }
  }

  return {
    control: (action: Control) => send((sid) => api.control(sid, action)),
    /** "Finish now": no more rounds after this one. */
    finish: () => send((sid) => api.finish(sid)),
    /** "Continue training" a finished session. */
    continueTraining: (body: ContinueIn) => send((sid) => api.continueTraining(sid, body)),
  };
}
