/**
 * The one store of the page: a plain state object, a pure reducer, subscribe/dispatch.
 * Every view derives from `State`; nothing else holds app state (views keep only DOM).
 */
import type {
  AgentOut,
  Annotator,
  AnnotatorCreated,
  ClipTiming,
  Edge,
  EnvInfo,
  JudgementOut,
  PairQuery,
  Revision,
  SessionState,
  Settings,
  TrainingPoint,
} from "./api";
import { type AnnotatorBoard, EMPTY_BOARD, withJudgementEvent, withSessionState } from "./lib/annotators";
import {
  type ArcClick,
  EMPTY_GROUPS,
  type GroupId,
  type Groups,
  clickArc,
  moveLeaf,
  otherGroup,
  removeLeaf,
} from "./lib/selection";
import type { Tree } from "./lib/tree";
import { centresOn } from "./lib/centre";
import { DEFAULT_BETA } from "./lib/edges";
import { FRESH_ORIGIN, type GroupChange, type Origin, arcChange, originAfter } from "./lib/origin";
import type { Schemas } from "./lib/settings-form";
import { mergePoints } from "./lib/training";

export type { Origin, Source } from "./lib/origin";
export { FRESH_ORIGIN } from "./lib/origin";

export interface Toast {
  id: number;
  kind: "ok" | "error" | "info";
  text: string;
  /** Offer "Undo" (the last answer). */
  undo?: boolean;
}

export interface RoundData {
  sid: string;
  round: number;
  tree: Tree;
  medoids: Record<string, string[]>;
  /** How the round's clips play (null: a pool from before it was recorded). */
  clip?: ClipTiming | null;
}

export interface ViewSettings {
  showSuggestions: boolean;
  showHistory: boolean;
  /** How many suggestion edges to draw. */
  k: number;
  /** Bundling strength of the edges. */
  beta: number;
  /** Playback rate of the clips. */
  speed: number;
}

export interface PairwiseState {
  current: PairQuery | null;
  following: PairQuery | null;
  loading: boolean;
  /** Pairs answered or skipped on this page ("left:right"): never shown again. */
  done: string[];
  /** When `current` was shown (ms). */
  shownAt: number | null;
  /** True once the server said there is no pair left. */
  exhausted: boolean;
  /** How the open round's clips play. */
  clip?: ClipTiming | null;
}

/** The owner's "Annotators" dialog: open or not, the person just added (their link is shown
 * once), a request in flight, and why the last one was refused. */
export interface PeopleState {
  open: boolean;
  created: AnnotatorCreated | null;
  busy: boolean;
  error: string | null;
}

/** The New-session form's answers from the server (the inputs themselves live in the DOM). */
export interface NewSessionState {
  /** The settings a session of the chosen env and settings would store. */
  resolved: Settings | null;
  /** Why the server would refuse the chosen env (shown next to it). */
  envError: string | null;
  /** Why it would refuse the chosen settings, or why creating failed. */
  error: string | null;
}

export interface State {
  boot: "loading" | "choose" | "ready" | "error";
  bootError: string | null;
  envs: EnvInfo[];
  /** The server's schemas (`SessionSettings` and what it nests), for the New-session form. */
  schemas: Schemas | null;
  newSession: NewSessionState;
  sessions: SessionState[];
  session: SessionState | null;
  /** When `session` arrived (ms), to run the round's timer between updates. */
  sessionAt: number;
  round: RoundData | null;
  suggestions: Edge[];
  /** This round's judgements, oldest first, undone ones removed. */
  judgements: JudgementOut[];
  groups: Groups;
  /** The group plain clicks fill. */
  target: GroupId;
  origin: Origin;
  suggestionStatus: "idle" | "loading" | "none";
  view: ViewSettings;
  hover: { id: string | null; from: "chart" | "clip" | null };
  /** The cluster the exploration chart is centred on (null: the whole round; issue 40). */
  centre: string | null;
  submitting: boolean;
  undoing: boolean;
  /** A control request (pause, resume, end round, retry, create) is in flight. */
  busy: boolean;
  toast: Toast | null;
  connection: "connecting" | "open" | "lost";
  pairwise: PairwiseState;
  /** The guide is open over the page (the answer keys rest meanwhile). */
  guide: boolean;
  /**
   * The finished session's agent, for the session and round of `key` ("sid:round"); `data`
   * null when the session has none (imported, or driven by a program).
   */
  agent: { key: string; data: AgentOut | null } | null;
  /** The session `sid`'s learning curve so far, in time order (`lib/training.ts`). */
  training: { sid: string; points: TrainingPoint[] } | null;
  /** Each person's counters and agreement, kept live between states (`lib/annotators.ts`). */
  annotators: AnnotatorBoard;
  /** Judgements this page just undid: an undone event finds their pairs here. */
  undone: JudgementOut[];
  people: PeopleState;
}

export const initialState: State = {
  boot: "loading",
  bootError: null,
  envs: [],
  schemas: null,
  newSession: { resolved: null, envError: null, error: null },
  sessions: [],
  session: null,
  sessionAt: 0,
  round: null,
  suggestions: [],
  judgements: [],
  groups: EMPTY_GROUPS,
  target: "A",
  origin: FRESH_ORIGIN,
  suggestionStatus: "idle",
  view: { showSuggestions: true, showHistory: true, k: 100, beta: DEFAULT_BETA, speed: 1 },
  hover: { id: null, from: null },
  centre: null,
  submitting: false,
  undoing: false,
  busy: false,
  toast: null,
  connection: "connecting",
  pairwise: {
    current: null,
    following: null,
    loading: false,
    done: [],
    shownAt: null,
    exhausted: false,
  },
  guide: false,
  agent: null,
  training: null,
  annotators: EMPTY_BOARD,
  undone: [],
  people: { open: false, created: null, busy: false, error: null },
};

export type Action =
  | { type: "boot"; boot: State["boot"]; error?: string }
  | { type: "envs"; envs: EnvInfo[] }
  | { type: "schemas"; schemas: Schemas }
  | { type: "new-session"; patch: Partial<NewSessionState> }
  | { type: "sessions"; sessions: SessionState[] }
  /** `rev`: the revision of a state event (null for a state read or a control's reply). */
  | { type: "session"; session: SessionState; at: number; rev?: Revision }
  | { type: "round-data"; round: RoundData }
  | { type: "suggestions"; edges: Edge[] }
  | { type: "judgements"; judgements: JudgementOut[] }
  | { type: "judgement-stored"; judgement: JudgementOut }
  | { type: "judgement-undone"; id: number }
  /** A judgement event of the stream (anyone's), at revision `rev`. */
  | { type: "judgement-event"; judgement: JudgementOut; rev: Revision }
  | { type: "people"; patch: Partial<PeopleState> }
  /** The session's people as `GET …/annotators` answered (after the events seen so far). */
  | { type: "annotators"; sid: string; list: Annotator[] }
  | { type: "select"; click: Omit<ArcClick, "target">; other: boolean; at: number }
  | { type: "remove"; id: string; at: number }
  | { type: "move"; id: string; at: number }
  | { type: "clear" }
  | { type: "set-groups"; groups: Groups; origin: Origin }
  | { type: "target"; group: GroupId | "switch" }
  | { type: "suggestion-status"; status: State["suggestionStatus"] }
  | { type: "view"; patch: Partial<ViewSettings> }
  | { type: "hover"; id: string | null; from: "chart" | "clip" | null }
  /** Centres the chart on a cluster (null: the whole round). */
  | { type: "centre"; id: string | null }
  | { type: "submitting"; value: boolean }
  | { type: "answered"; judgement: JudgementOut }
  | { type: "undoing"; value: boolean }
  | { type: "busy"; value: boolean }
  | { type: "toast"; kind: Toast["kind"]; text: string; undo?: boolean }
  | { type: "dismiss-toast"; id?: number }
  | { type: "connection"; value: State["connection"] }
  | { type: "pairwise"; patch: Partial<PairwiseState> }
  | { type: "guide"; open: boolean }
  | { type: "agent"; key: string; agent: AgentOut | null }
  | { type: "training"; sid: string; points: TrainingPoint[] };

let toastId = 0;

/** The groups after a change, and where they now come from (`lib/origin.ts`). */
function withGroups(state: State, groups: Groups, change: GroupChange, at: number): State {
  return { ...state, groups, origin: originAfter(state.origin, change, groups, at) };
}

function toast(state: State, kind: Toast["kind"], text: string, undo = false): State {
  return { ...state, toast: { id: ++toastId, kind, text, ...(undo ? { undo } : {}) } };
}

function upsert(list: JudgementOut[], j: JudgementOut): JudgementOut[] {
  if (list.some((x) => x.id === j.id)) return list;
  return [...list, j].sort((a, b) => a.id - b.id);
}

export function reduce(state: State, action: Action): State {
  switch (action.type) {
    case "boot":
      return { ...state, boot: action.boot, bootError: action.error ?? null };
    case "envs":
      return { ...state, envs: action.envs };
    case "schemas":
      return { ...state, schemas: action.schemas };
    case "new-session":
      return { ...state, newSession: { ...state.newSession, ...action.patch } };
    case "sessions":
      return { ...state, sessions: action.sessions };
    case "session": {
      const other = state.session?.id !== action.session.id;
      const board = withSessionState(other ? EMPTY_BOARD : state.annotators, action.session.annotators, action.rev ?? null);
      return { ...state, session: action.session, sessionAt: action.at, annotators: board };
    }
    case "round-data": {
      const sameRound =
        state.round?.sid === action.round.sid && state.round?.round === action.round.round;
      return sameRound
        ? { ...state, round: action.round }
        : {
            ...state,
            round: action.round,
            suggestions: [],
            judgements: [],
            groups: EMPTY_GROUPS,
            origin: FRESH_ORIGIN,
            suggestionStatus: "idle",
            hover: { id: null, from: null },
            centre: null,
          };
    }
    case "suggestions":
      return { ...state, suggestions: action.edges };
    case "judgements":
      return { ...state, judgements: action.judgements.filter((j) => !j.undone) };
    case "judgement-stored":
      if (state.round && action.judgement.round !== state.round.round) return state;
      return { ...state, judgements: upsert(state.judgements, action.judgement) };
    case "judgement-undone": {
      const gone = state.judgements.find((j) => j.id === action.id);
      return {
        ...state,
        judgements: state.judgements.filter((j) => j.id !== action.id),
        undone: gone ? [...state.undone, gone].slice(-20) : state.undone,
      };
    }
    case "judgement-event": {
      const j = action.judgement;
      const known = j.undone
        ? (state.judgements.find((x) => x.id === j.id) ?? state.undone.find((x) => x.id === j.id))
        : undefined;
      const annotators = withJudgementEvent(state.annotators, j, action.rev, known);
      const next = reduce({ ...state, annotators }, j.undone ? { type: "judgement-undone", id: j.id } : { type: "judgement-stored", judgement: j });
      return next;
    }
    case "annotators":
      if (state.session?.id !== action.sid) return state;
      return { ...state, annotators: withSessionState(state.annotators, action.list, null) };
    case "people":
      return { ...state, people: { ...state.people, ...action.patch } };
    case "select": {
      // A cluster too big to be a group: the click centres the chart on it (issue 40).
      if (centresOn(action.click) && action.click.id !== undefined) return reduce(state, { type: "centre", id: action.click.id });
      const click = { ...action.click, target: action.other ? otherGroup(state.target) : state.target };
      const r = clickArc(state.groups, click);
      if (r.message) return toast(state, "info", r.message);
      return r.changed ? withGroups(state, r.groups, arcChange(click), action.at) : state;
    }
    case "remove":
    case "move": {
      const r = (action.type === "remove" ? removeLeaf : moveLeaf)(state.groups, action.id);
      if (r.message) return toast(state, "info", r.message);
      return r.changed ? withGroups(state, r.groups, "edit", action.at) : state;
    }
    case "clear":
      return { ...state, groups: EMPTY_GROUPS, origin: FRESH_ORIGIN };
    case "set-groups":
      return { ...state, groups: action.groups, origin: action.origin };
    case "target":
      return {
        ...state,
        target: action.group === "switch" ? otherGroup(state.target) : action.group,
      };
    case "suggestion-status":
      return { ...state, suggestionStatus: action.status };
    case "view":
      return { ...state, view: { ...state.view, ...action.patch } };
    case "centre":
      return state.centre === action.id ? state : { ...state, centre: action.id, hover: { id: null, from: null } };
    case "hover":
      if (state.hover.id === action.id && state.hover.from === action.from) return state;
      return { ...state, hover: { id: action.id, from: action.from } };
    case "submitting":
      return { ...state, submitting: action.value };
    case "answered": {
      const j = action.judgement;
      const next: State = {
        ...state,
        submitting: false,
        judgements: upsert(state.judgements, j),
        groups: EMPTY_GROUPS,
        origin: FRESH_ORIGIN,
        suggestionStatus: "idle",
      };
      const what =
        j.label === "equal" ? "equal" : j.label === "left" ? "left better" : "right better";
      const pairs = j.pairs.length === 1 ? "1 preference pair" : `${j.pairs.length} preference pairs`;
      return toast(next, "ok", `Saved: ${what} · ${pairs}.`, true);
    }
    case "undoing":
      return { ...state, undoing: action.value };
    case "busy":
      return { ...state, busy: action.value };
    case "toast":
      return toast(state, action.kind, action.text, action.undo ?? false);
    case "dismiss-toast":
      if (!state.toast || (action.id !== undefined && state.toast.id !== action.id)) return state;
      return { ...state, toast: null };
    case "connection":
      return state.connection === action.value ? state : { ...state, connection: action.value };
    case "pairwise":
      return { ...state, pairwise: { ...state.pairwise, ...action.patch } };
    case "guide":
      return state.guide === action.open ? state : { ...state, guide: action.open };
    case "agent":
      return { ...state, agent: { key: action.key, data: action.agent } };
    case "training": {
      const before = state.training?.sid === action.sid ? state.training.points : [];
      return { ...state, training: { sid: action.sid, points: mergePoints(before, action.points) } };
    }
  }
}

export type Listener = (state: State, previous: State) => void;

export interface Store {
  getState(): State;
  dispatch(action: Action): void;
  subscribe(listener: Listener): () => void;
}

export function createStore(initial: State = initialState): Store {
  let state = initial;
  const listeners = new Set<Listener>();
  return {
    getState: () => state,
    dispatch(action) {
      const previous = state;
      state = reduce(state, action);
      if (state !== previous) for (const l of [...listeners]) l(state, previous);
    },
    subscribe(listener) {
      listeners.add(listener);
      return () => listeners.delete(listener);
    },
  };
}

/** Behaviours of this round already in a judgement (history), for the "not compared" marks. */
export function comparedLeaves(judgements: readonly JudgementOut[]): Set<string> {
  const out = new Set<string>();
  for (const j of judgements) for (const id of [...j.left, ...j.right]) out.add(id);
  return out;
}
