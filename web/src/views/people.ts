/**
 * The people of a shared session (issue 21), under the comparison (under the pair in
 * pairwise mode): each person's comparisons, preference pairs and time, their agreement with
 * the others (Cohen's κ and the share alike, on the n behaviour pairs both judged) and with
 * the reward model; and under them the round's comparisons newest first, each with its
 * person's initials in their colour (the whole judgement in its title). Counters come from the store, kept live by the event stream.
 */
import type { Annotator, JudgementOut } from "../api";
import {
  type HistoryRow,
  OWNER_COLOUR,
  agreementText,
  agreementTitle,
  historyRows,
  initials,
  modelAgreementText,
} from "../lib/annotators";
import { clock } from "../lib/format";
import { h, memo, text } from "./dom";

export interface PeopleData {
  shared: boolean;
  people: readonly Annotator[];
  meId: string;
  colours: ReadonlyMap<string, string>;
  judgements: readonly JudgementOut[];
  mode: "groupwise" | "pairwise";
  round: number;
}

interface View {
  body: HTMLTableSectionElement;
  history: HTMLOListElement;
  historyTitle: HTMLElement;
  empty: HTMLElement;
  rows: Map<string, HTMLTableRowElement>;
  lastPeople: readonly Annotator[] | null;
  lastJudgements: readonly JudgementOut[] | null;
}

const views = new WeakMap<Element, View>();
/** The history list keeps its newest rows; older ones are in the export. */
const HISTORY_ROWS = 50;

export function renderPeople(element: HTMLElement, data: PeopleData): void {
  element.hidden = !data.shared;
  if (!data.shared) return;
  const view = memo(views, element, () => build(element));
  if (view.lastPeople !== data.people) {
    view.lastPeople = data.people;
    renderTable(view, data);
  }
  if (view.lastJudgements !== data.judgements) {
    view.lastJudgements = data.judgements;
    renderHistory(view, data);
  }
  text(view.historyTitle, `Round ${data.round}, newest first:`);
}

export function badge(name: string, colour: string): HTMLElement {
  const el = h("span", { class: "person-badge", "aria-hidden": "true" }, initials(name));
  el.style.background = colour;
  return el;
}

function renderTable(view: View, data: PeopleData): void {
  const seen = new Set<string>();
  const rows: HTMLTableRowElement[] = [];
  for (const p of data.people) {
    seen.add(p.id);
    let tr = view.rows.get(p.id);
    if (!tr) {
      tr = h("tr", { "data-id": p.id });
      view.rows.set(p.id, tr);
    }
    const you = p.id === data.meId;
    tr.classList.toggle("me", you);
    tr.replaceChildren(
      h(
        "th",
        { scope: "row", class: "person" },
        badge(p.name, data.colours.get(p.id) ?? OWNER_COLOUR),
        h("span", { class: "person-name" }, p.name),
        you ? h("span", { class: "muted you" }, " (you)") : null,
      ),
      h("td", { class: "num comparisons" }, String(p.comparisons)),
      h("td", { class: "num pairs" }, String(p.pairs)),
      h("td", { class: "num shown" }, clock(p.shown_s)),
      h("td", { class: "num agreement", title: agreementTitle(p) }, agreementText(p.agreement)),
      h("td", { class: "num model", title: agreementTitle(p) }, modelAgreementText(p.model_agreement)),
    );
    rows.push(tr);
  }
  for (const id of [...view.rows.keys()]) if (!seen.has(id)) view.rows.delete(id);
  view.body.replaceChildren(...rows);
}

function renderHistory(view: View, data: PeopleData): void {
  const rows = historyRows(data.judgements, data.colours, data.meId, data.mode).slice(0, HISTORY_ROWS);
  view.empty.hidden = rows.length > 0;
  view.history.replaceChildren(...rows.map(historyItem));
}

function historyItem(row: HistoryRow): HTMLLIElement {
  return h(
    "li",
    { class: `history-row${row.mine ? " mine" : ""}`, title: row.title, "data-annotator": row.who.id, "data-id": row.id },
    badge(row.who.name, row.colour),
    h("span", { class: "sr-only" }, `${row.who.name}: `),
    h("span", { class: "history-text" }, row.text),
  );
}

function build(element: HTMLElement): View {
  element.classList.add("panel", "people-panel");
  element.setAttribute("aria-label", "Annotators");
  const body = h("tbody", {});
  const table = h(
    "table",
    { class: "people-table" },
    h("caption", { class: "sr-only" }, "Each person's comparisons, pairs, time and agreement"),
    h(
      "thead",
      {},
      h(
        "tr",
        {},
        h("th", { scope: "col" }, "Person"),
        h("th", { scope: "col", class: "num", title: "Comparisons this person made in the session" }, "Comp."),
        h("th", { scope: "col", class: "num", title: "Training pairs: the preference pairs the reward model learns from, max(m, n) per comparison of m and n behaviours" }, "Pairs"),
        h("th", { scope: "col", class: "num", title: "Time the rounds were on their screen: from their first showing of each round to its close" }, "Time"),
        h(
          "th",
          { scope: "col", class: "num", title: "Agreement with the others on the behaviour pairs both judged: Cohen's κ, and the share alike of n pairs" },
          "With others",
        ),
        h("th", { scope: "col", class: "num", title: "Share of the behaviour pairs they compared (each left behaviour with each right one) where the reward model prefers the same behaviour" }, "Reward model"),
      ),
    ),
    body,
  );
  const historyTitle = h("span", { class: "history-title", id: "people-history-title" });
  const history = h("ol", { class: "history-list", "aria-labelledby": "people-history-title" });
  const empty = h("span", { class: "muted history-empty" }, "no comparison yet");
  element.replaceChildren(
    h("div", { class: "people-main" }, table),
    h("div", { class: "people-history" }, historyTitle, history, empty),
  );
  return { body, history, historyTitle, empty, rows: new Map(), lastPeople: null, lastJudgements: null };
}
