/**
 * What every effect module is given: the one store, the server (`api.ts`, the only module
 * doing I/O) and how a failure reaches the person.
 */
import type { Api } from "../api";
import type { Store } from "../state";

export interface EffectContext {
  readonly store: Store;
  readonly api: Api;
  /** Shows a failure's message as an error toast. */
  fail(err: unknown): void;
}

export function createContext(store: Store, api: Api): EffectContext {
  return {
    store,
    api,
    fail(err) {
      const text = err instanceof Error ? err.message : String(err);
      store.dispatch({ type: "toast", kind: "error", text });
    },
  };
}
