/**
 * Effects: everything that reaches the server and feeds the answers into the store, composed
 * from `effects/` (one module per job). Views call these through their handlers; only
 * `api.ts` below this layer does I/O, and `state.ts` holds all state.
 */
import type { Api } from "./api";
import type { Store } from "./state";
import { createAnswers } from "./effects/answers";
import { createContext } from "./effects/context";
import { createControls } from "./effects/controls";
import { createEventStream } from "./effects/events";
import { createGroups } from "./effects/groups";
import { createPageSettings } from "./effects/page-settings";
import { createPairwiseFlow } from "./effects/pairwise-flow";
import { createPeople } from "./effects/people";
import { createRoundSync } from "./effects/round";
import { createSessions } from "./effects/sessions";
import { createTakeaway } from "./effects/takeaway";

export interface ControllerOptions {
  annotator?: string;
  /** Where the selected groups, the playback speed and the group clicks fill survive a
   * reload (sessionStorage by default). */
  storage?: Pick<Storage, "getItem" | "setItem"> | null;
  /** Puts the session id in the address bar. */
  setUrl?(sid: string | null): void;
  /** Whether the page can be seen now (default: the document is not hidden). */
  visible?(): boolean;
}

export function createController(store: Store, api: Api, options: ControllerOptions = {}) {
  const annotator = options.annotator ?? "";
  const storage = options.storage === undefined ? globalThis.sessionStorage ?? null : options.storage;
  const visible = options.visible ?? (() => globalThis.document?.visibilityState !== "hidden");
  const setUrl = (sid: string | null) => options.setUrl?.(sid);

  const ctx = createContext(store, api);
  const pairwise = createPairwiseFlow(ctx, annotator);
  const groups = createGroups(ctx, storage);
  const round = createRoundSync(ctx, groups, pairwise, visible);
  const people = createPeople(ctx, groups, pairwise, visible);
  const events = createEventStream(ctx, round, people);
  const pageSettings = createPageSettings(ctx, storage);
  const sessions = createSessions(ctx, events, round, setUrl, pageSettings);
  const answers = createAnswers(ctx, annotator, groups, pairwise);
  const controls = createControls(ctx, round);
  const takeaway = createTakeaway(ctx);

  return {
    boot: sessions.boot,
    open: sessions.open,
    create: sessions.create,
    checkNewSession: sessions.checkNewSession,
    showStart: sessions.showStart,
    suggest: groups.suggest,
    answer: answers.answer,
    undo: answers.undo,
    reportShown: round.reportShown,
    answerPair: pairwise.answer,
    skipPair: pairwise.skip,
    control: controls.control,
    finish: controls.finish,
    continueTraining: controls.continueTraining,
    pickAgent: takeaway.pick,
    lastJudgement: answers.lastJudgement,
    addAnnotator: people.add,
    removeAnnotator: people.remove,
    refreshAnnotators: people.refresh,
  };
}

export type Controller = ReturnType<typeof createController>;
