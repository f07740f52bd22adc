/**
 * The open session's event stream (SSE): state changes, judgements stored or undone
 * elsewhere, new rounds and the agent's learning curve reach the store; after a drop the
 * state and the curve are read again, since events were missed meanwhile.
 */
import { STALE } from "../api";
import type { EffectContext } from "./context";
import type { PeopleEffects } from "./people";
import type { RoundSync } from "./round";

export function createEventStream({ store, api, fail }: EffectContext, round: RoundSync, people: PeopleEffects) {
  const dispatch = store.dispatch;
  const get = store.getState;
  let closeEvents: (() => void) | null = null;

  /** Listens to session `sid` (the caller closed any earlier stream). */
  function connect(sid: string): void {
    dispatch({ type: "connection", value: "connecting" });
    void loadTraining(sid);
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
      state(session, rev) {
        if (session.id !== get().session?.id) return;
        dispatch({ type: "session", session, at: Date.now(), rev });
        void round.sync();
        void round.syncAgent();
        void round.reportShown();
      },
      judgement(j, rev) {
        if (get().session?.id !== sid) return;
        dispatch({ type: "judgement-event", judgement: j, rev });
        void people.answeredElsewhere(j);
      },
      round() {
        void resync(sid);
      },
      training(point) {
        if (get().session?.id === sid) dispatch({ type: "training", sid, points: [point] });
      },
    });
  }

  async function resync(sid: string): Promise<void> {
    try {
      const session = await api.session(sid);
      if (session === STALE || get().session?.id !== sid) return;
      dispatch({ type: "session", session, at: Date.now() });
      await Promise.all([round.sync(), loadTraining(sid)]);
    } catch (err) {
      fail(err);
    }
  }

  async function loadTraining(sid: string): Promise<void> {
    try {
      const curve = await api.training(sid);
      if (curve === STALE || get().session?.id !== sid) return;
      dispatch({ type: "training", sid, points: curve.points });
    } catch (err) {
      fail(err);
    }
  }

  function close(): void {
    closeEvents?.();
    closeEvents = null;
  }

  return { connect, close };
}

export type EventStream = ReturnType<typeof createEventStream>;
