/**
 * The take-away agent (issue 20): the person makes a round's policy the finished session's
 * download (`PUT …/agent/round`); the store's agent becomes the server's answer, so the
 * results page's video, numbers and choice follow it.
 */
import type { AgentOut } from "../api";
import type { EffectContext } from "./context";

export function createTakeaway({ store, api }: EffectContext) {
  /** Round `round`'s agent becomes the download. Resolves to the new agent; rejects with an
   * `ApiError` whose message says why not (404: no such round; 409: not finished, or the
   * round's checkpoint is gone), for the results page to show beside the rounds. */
  async function pick(round: number): Promise<AgentOut> {
    const s = store.getState().session;
    if (!s) throw new Error("No session is open.");
    const key = `${s.id}:${s.round}`;
    const agent = await api.pickAgent(s.id, round);
    // The session moved on meanwhile (it trains again): its next agent is loaded anew.
    if (store.getState().agent?.key === key) store.dispatch({ type: "agent", key, agent });
    return agent;
  }

  return { pick };
}
