/**
 * Several people teaching one agent (issue 21), the pure part: who made a judgement, each
 * person's initials and colour, the per-person counters kept live from the event stream,
 * agreement in words, and which suggestion or pair someone else's answer used up.
 *
 * The counters come whole with every session state (`SessionState.annotators`); between two
 * states the page adds each judgement event to them (`withJudgementEvent`). Events and
 * states carry the session's revision (the SSE `id:`), so an event the last state already
 * counted is not counted again, and a state older than the counters is not taken.
 */
import type { Annotator, AnnotatorRef, JudgementOut, Me, SessionState } from "../api";
import type { Groups } from "./selection";

/** The id the session's owner has among the annotators. */
export const OWNER_ID = "owner";

/** Who made a judgement; a judgement from before shared sessions is the owner's. */
export function judgementAnnotator(j: Pick<JudgementOut, "annotator">): AnnotatorRef {
  const a = j.annotator as unknown; // a string from a server before shared sessions
  if (a && typeof a === "object" && typeof (a as AnnotatorRef).id === "string") {
    const ref = a as AnnotatorRef;
    return { id: ref.id, name: ref.name };
  }
  return { id: OWNER_ID, name: typeof a === "string" && a ? a : "owner" };
}

/** Who this page is: the session's `me`, else (a server without shared sessions) the owner. */
export function meOf(s: Partial<Pick<SessionState, "me">> | null | undefined): Me {
  return s?.me ?? { id: OWNER_ID, name: "owner", owner: true };
}

/** A session is shared once it has an annotator besides its owner, or this page is one. */
export function isShared(s: Partial<Pick<SessionState, "me" | "annotators">> | null | undefined): boolean {
  if (!s) return false;
  return !meOf(s).owner || (s.annotators ?? []).some((a) => a.id !== OWNER_ID);
}

/** One or two letters for a name: "Ada Lovelace" → "AL", "bob" → "B", "" → "?". */
export function initials(name: string): string {
  const words = name.trim().split(/[\s._-]+/u).filter(Boolean);
  const first = (w: string | undefined) => (w ? Array.from(w)[0]!.toLocaleUpperCase() : "");
  const out = first(words[0]) + (words.length > 1 ? first(words[words.length - 1]) : "");
  return out || "?";
}

/**
 * Badge colours, dark enough for white letters, away from the groups' orange and green and
 * from the history edges' blue → red; the letters are the cue that needs no colour.
 */
export const ANNOTATOR_COLOURS = [
  "#5b4b8a",
  "#2f6f86",
  "#8a4b6e",
  "#6b6b2f",
  "#3f5f9f",
  "#7a4f2f",
  "#2f7a5a",
  "#8a3f3f",
] as const;
export const OWNER_COLOUR = "#344054";

/**
 * A colour per annotator id: the owner's own, the others by their place in `ids` (the
 * session's list, which keeps its order), so every page gives a person the same colour.
 */
export function annotatorColours(ids: readonly string[]): Map<string, string> {
  const out = new Map<string, string>();
  let i = 0;
  for (const id of ids) {
    if (out.has(id)) continue;
    out.set(id, id === OWNER_ID ? OWNER_COLOUR : ANNOTATOR_COLOURS[i++ % ANNOTATOR_COLOURS.length]!);
  }
  return out;
}

/* ---------------------------------------------------------------- live counters */

/** The per-person counters the page shows, and the revision they are as of (null: unknown). */
export interface AnnotatorBoard {
  list: Annotator[];
  rev: number | null;
}

export const EMPTY_BOARD: AnnotatorBoard = { list: [], rev: null };

/**
 * The counters of a session state at revision `rev` (null for a state read by GET, which the
 * page asks for only after the events it has seen). An older state than the board is dropped.
 */
export function withSessionState(board: AnnotatorBoard, list: readonly Annotator[] | undefined, rev: number | null): AnnotatorBoard {
  if (list === undefined) return board;
  if (rev !== null && board.rev !== null && rev < board.rev) return board;
  return { list: [...list], rev: rev ?? board.rev };
}

function fresh(ref: AnnotatorRef): Annotator {
  return {
    id: ref.id,
    name: ref.name,
    comparisons: 0,
    pairs: 0,
    shown_s: 0,
    agreement: { kappa: null, share: null, n: 0 },
    model_agreement: { share: null, n: 0 },
  };
}

/**
 * The counters after a judgement event at revision `rev`: a stored judgement adds one
 * comparison and its pairs to its annotator; an undone one takes them off again (`known`:
 * the judgement as it was stored, since an undone one comes without its pairs). An event the
 * board already holds (rev ≤ board.rev) changes nothing. Time shown and agreement are left
 * as they are: the next state brings them.
 */
export function withJudgementEvent(
  board: AnnotatorBoard,
  j: JudgementOut,
  rev: number | null,
  known?: JudgementOut,
): AnnotatorBoard {
  if (rev !== null && board.rev !== null && rev <= board.rev) return board;
  const who = judgementAnnotator(j);
  const sign = j.undone ? -1 : 1;
  const source = j.undone ? known : j;
  if (j.undone && !known) return rev === null ? board : { ...board, rev };
  const list = board.list.some((a) => a.id === who.id) ? [...board.list] : [...board.list, fresh(who)];
  const i = list.findIndex((a) => a.id === who.id);
  const a = list[i]!;
  list[i] = {
    ...a,
    comparisons: Math.max(0, a.comparisons + sign),
    pairs: Math.max(0, a.pairs + sign * (source?.pairs.length ?? 0)),
  };
  return { list, rev: rev ?? board.rev };
}

/* ---------------------------------------------------------------- words */

const pct = (share: number) => `${Math.round(share * 100)} %`;

/** κ with two decimals ("0.62", "−0.10"), or "–" when it cannot be computed. */
export function kappaText(kappa: number | null): string {
  if (kappa === null || !Number.isFinite(kappa)) return "–";
  const v = kappa.toFixed(2);
  return v.startsWith("-") ? `−${v.slice(1)}` : v;
}

/**
 * Agreement with the others as a table cell: "κ 0.62 · 80 % of 10"; "no overlap yet" when no
 * behaviour pair was judged by this person and someone else.
 */
export function agreementText(a: Annotator["agreement"]): string {
  if (a.n === 0 || a.share === null) return "no overlap yet";
  return `κ ${kappaText(a.kappa)} · ${pct(a.share)} of ${a.n}`;
}

/**
 * Agreement with the reward model: "75 % of 8 compared pairs", or "–" before it has anything
 * to go on. Its unit is the behaviour pairs a person compared (each left behaviour with each
 * right one), not the "Pairs" column's training pairs (max(m, n) a comparison; issue 40).
 */
export function modelAgreementText(m: Annotator["model_agreement"]): string {
  if (m.n === 0 || m.share === null) return "–";
  return `${pct(m.share)} of ${m.n} compared pairs`;
}

/** The whole sentence, for a title or a screen reader. */
export function agreementTitle(a: Annotator): string {
  const others =
    a.agreement.n === 0 || a.agreement.share === null
      ? "has judged no behaviour pair someone else judged too"
      : `agrees with the others on ${pct(a.agreement.share)} of ${a.agreement.n} behaviour pairs both judged ` +
        `(Cohen's κ ${kappaText(a.agreement.kappa)})`;
  const model =
    a.model_agreement.n === 0 || a.model_agreement.share === null
      ? "the reward model has not been compared with them yet"
      : `the reward model prefers the same behaviour in ${pct(a.model_agreement.share)} of the ${a.model_agreement.n} ` +
        "behaviour pairs they compared (each left behaviour with each right one)";
  return `${a.name} ${others}; ${model}.`;
}

/* ---------------------------------------------------------------- history */

export interface HistoryRow {
  id: number;
  who: AnnotatorRef;
  initials: string;
  colour: string;
  mine: boolean;
  /** "A better · 3 vs 2", "equal · b4 vs b9". */
  text: string;
  /** The whole judgement in words. */
  title: string;
}

const LABEL_WORDS = { left: "A better", right: "B better", equal: "equal" } as const;
const PAIR_WORDS = { left: "left better", right: "right better", equal: "equal" } as const;

function side(ids: readonly string[]): string {
  return ids.length === 1 ? ids[0]! : `${ids.length}`;
}

/** The round's judgements as the history list shows them, newest first. */
export function historyRows(
  judgements: readonly JudgementOut[],
  colours: ReadonlyMap<string, string>,
  meId: string,
  mode: "groupwise" | "pairwise",
): HistoryRow[] {
  return [...judgements].reverse().map((j) => {
    const who = judgementAnnotator(j);
    const label = (mode === "pairwise" ? PAIR_WORDS : LABEL_WORDS)[j.label];
    const pairs = j.pairs.length === 1 ? "1 pair" : `${j.pairs.length} pairs`;
    return {
      id: j.id,
      who,
      initials: initials(who.name),
      colour: colours.get(who.id) ?? OWNER_COLOUR,
      mine: who.id === meId,
      text: `${label} · ${side(j.left)} vs ${side(j.right)}`,
      title: `${who.name}${who.id === meId ? " (you)" : ""}: ${j.left.join(", ")} vs ${j.right.join(", ")} · ${label} · ${pairs} · ${Math.round(j.seconds)} s`,
    };
  });
}

/* ---------------------------------------------------------------- answers elsewhere */

/** The suggestion a judgement answered, when the server says so. */
export function answeredSuggestion(j: Pick<JudgementOut, "suggestion_id">): number | null {
  return j.suggestion_id ?? null;
}

const sameSet = (a: readonly string[], b: readonly string[]) =>
  a.length === b.length && a.every((id) => b.includes(id));

/**
 * What to do with the groups on screen when someone else's judgement `j` arrives: `replace`
 * them by the next suggestion when they are the suggestion it answered, untouched; `keep`
 * them, with a word, when the person already edited that suggestion; otherwise nothing.
 */
export function afterAnswerElsewhere(
  groups: Groups,
  origin: { source: string; edits: number; suggestion: { id?: number | null; left: string[]; right: string[] } | null },
  j: JudgementOut,
  meId: string,
): "replace" | "keep" | null {
  if (j.undone || judgementAnnotator(j).id === meId) return null;
  const sug = origin.suggestion;
  if (!sug || origin.source !== "suggested") return null;
  const answered = answeredSuggestion(j);
  const same =
    answered !== null && sug.id !== undefined && sug.id !== null
      ? answered === sug.id
      : (sameSet(j.left, sug.left) && sameSet(j.right, sug.right)) ||
        (sameSet(j.left, sug.right) && sameSet(j.right, sug.left));
  if (!same) return null;
  const untouched = origin.edits === 0 && sameSet(groups.A, sug.left) && sameSet(groups.B, sug.right);
  return untouched ? "replace" : "keep";
}

/** Whether judgement `j` answered the pair `p` (either order). */
export function answersPair(j: Pick<JudgementOut, "left" | "right">, p: { left: string; right: string }): boolean {
  if (j.left.length !== 1 || j.right.length !== 1) return false;
  const [l, r] = [j.left[0], j.right[0]];
  return (l === p.left && r === p.right) || (l === p.right && r === p.left);
}

/**
 * The judgement "undo" takes back: this page's person's last one of the round; when they
 * have none, the round's last one (the server refuses another person's, and says why).
 */
export function undoTarget(judgements: readonly JudgementOut[], meId: string): JudgementOut | null {
  for (let i = judgements.length - 1; i >= 0; i--) {
    if (judgementAnnotator(judgements[i]!).id === meId) return judgements[i]!;
  }
  return judgements.at(-1) ?? null;
}
