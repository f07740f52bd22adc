/**
 * The status bar: session, round and phase, the round's timer (pause / resume), counters of
 * comparisons and preference pairs (this round and in total), "End round" and "Finish now"
 * (each asks for a second click: "Click again"), and "?" (the guide).
 *
 * One line at 1366 px whatever it says (docs/app.md, "Front end"): only the env name gives
 * way, cut with an ellipsis (the full name in its title), and a two-click button is as wide
 * in both its texts. Once the session is finishing or finished, the round's timer, counters
 * and "End round" are gone.
 *
 * A shared session (issue 21): who this page is (a badge and the name); for the owner the
 * name is on "Annotators" (add a person, copy their link, remove one), which reads so until
 * the session is shared; an annotator's page has no Pause, End round, Finish now or sessions
 * list, which are the owner's.
 */
import type { Me, SessionState } from "../api";
import { initials } from "../lib/annotators";
import { clock, elapsedNow, roundOf } from "../lib/format";
import type { State } from "../state";
import { attr, h, memo, s, text } from "./dom";

export interface StatusData {
  session: SessionState | null;
  sessionAt: number;
  connection: State["connection"];
  /** A control request (pause, end round…) is in flight. */
  busy: boolean;
  /** Who this page is, and whether the session has other people. */
  me: Me;
  shared: boolean;
  /** The people besides the owner; the colour of this page's badge. */
  annotators: number;
  colour: string;
}

export interface StatusHandlers {
  pause(): void;
  resume(): void;
  endRound(): void;
  /** No more rounds after this one: the final phase, then the agent. */
  finish(): void;
  sessions(): void;
  guide(): void;
  /** The owner's "Annotators" dialog. */
  people(): void;
}

interface View {
  meta: HTMLElement;
  timerWrap: HTMLElement;
  counts: HTMLElement;
  round: HTMLElement;
  phase: HTMLElement;
  timer: HTMLElement;
  pause: HTMLButtonElement;
  comparisons: HTMLElement;
  pairs: HTMLElement;
  end: HTMLButtonElement;
  finish: HTMLButtonElement;
  conn: HTMLElement;
  help: HTMLButtonElement;
  brand: HTMLButtonElement;
  who: HTMLElement;
  badge: HTMLElement;
  whoName: HTMLElement;
  people: HTMLButtonElement;
  peopleIcon: SVGSVGElement;
  peopleBadge: HTMLElement;
  peopleLabel: HTMLElement;
  data: StatusData | null;
  handlers: StatusHandlers | null;
  confirmUntil: number;
  finishConfirmUntil: number;
}

const views = new WeakMap<Element, View>();
const CONFIRM_MS = 4000;
/** What a two-click button reads while it waits for the second click. */
const AGAIN = "Click again";
const CONNECTION: Record<State["connection"], string> = {
  open: "live",
  connecting: "connecting…",
  lost: "reconnecting…",
};

/**
 * "Round 2 of 0–4": numbered from 0, as in the API and the export (`roundOf`); the rounds
 * without feedback after the last one (the final phase) are "Round 5 · final phase".
 */
export function roundText(s: Pick<SessionState, "round" | "rounds">): string {
  if (s.round >= s.rounds) return `Round ${s.round} · final phase`;
  return `Round ${roundOf(s.round, s.rounds)}`;
}

/** Whether the session's rounds are over: the final phase runs or ran, so the round's timer,
 * counters and "End round" no longer apply. */
export function roundsOver(s: Pick<SessionState, "phase">): boolean {
  return s.phase === "finishing" || s.phase === "finished";
}

/** Whether "Finish now" can end the session after its current round. */
export function canFinish(s: SessionState): boolean {
  if (s.settings.driver === "library") return false;
  return s.phase === "ready" || s.phase === "training" || (s.phase === "preparing" && s.round > 0);
}

const ROUND_TITLE =
  "Rounds are numbered from 0, as in the progress messages, the export and the checkpoint " +
  "folders (round-0000)";

export function renderStatus(element: HTMLElement, data: StatusData, handlers: StatusHandlers): void {
  const view = memo(views, element, () => build(element));
  view.data = data;
  view.handlers = handlers;
  const s = data.session;
  element.hidden = false;
  text(view.meta, s ? `${s.env} · ${s.mode}` : "");
  view.meta.title = s ? `${s.env} · ${s.mode} · session ${s.id}` : "";
  text(view.round, s ? roundText(s) : "");
  text(view.phase, s ? s.phase : "");
  view.phase.className = `phase phase-${s?.phase ?? "none"}`;
  if (s) {
    const c = s.counts;
    const budget = s.settings.comparisons_per_round;
    text(view.comparisons, `${c.comparisons_round}${budget ? ` / ${budget}` : ""}`);
    view.comparisons.nextElementSibling!.textContent = `${c.comparisons_total} total`;
    text(view.pairs, String(c.pairs_round));
    view.pairs.nextElementSibling!.textContent = `${c.pairs_total} total`;
  }
  const over = !!s && roundsOver(s);
  const owner = data.me.owner;
  view.timerWrap.hidden = over;
  view.counts.hidden = over;
  view.end.hidden = over || !owner;
  // Who this page is: an annotator's name beside the counters; the owner's on their
  // "Annotators" button (one control, so the bar keeps one line at 1366 px).
  view.who.hidden = !data.shared || owner;
  for (const b of [view.badge, view.peopleBadge]) {
    text(b, initials(data.me.name));
    b.style.background = data.colour;
  }
  text(view.whoName, data.me.name);
  view.who.title = `You are ${data.me.name}, an annotator of this shared session`;
  // An icon until the session is shared (the bar has no room for a word in its widest
  // states), then this person's initials and name.
  view.people.hidden = !owner || !s;
  view.peopleBadge.hidden = !data.shared;
  view.peopleLabel.hidden = !data.shared;
  attr(view.peopleIcon, "display", data.shared ? "none" : null);
  view.people.classList.toggle("shared", data.shared);
  text(view.peopleLabel, data.me.name);
  attr(view.people, "aria-label", data.shared ? `Annotators · you are ${data.me.name}, the owner` : "Annotators");
  view.people.title = data.shared
    ? `You are ${data.me.name}, the session's owner. Annotators (${data.annotators} besides you): add a person, copy their link, remove one`
    : "Annotators: share this session with other people, each with a link of their own";
  fitPeople(view, element);
  view.brand.disabled = !owner;
  view.brand.title = owner ? "Sessions" : "Sessions: the owner's";
  const ready = s?.phase === "ready";
  view.pause.disabled = !ready || data.busy;
  view.pause.hidden = !owner; // the owner's (403 for an annotator)
  const paused = s?.timer.paused ?? false;
  text(view.pause, paused ? "Resume" : "Pause");
  // Pause stops the round's timer and the agent's training (issue 39)
  attr(view.pause, "aria-label", paused ? "Resume the round timer and training" : "Pause the round timer and training");
  view.end.disabled = !ready || data.busy;
  if (!ready) resetConfirm(view);
  const finishable = !!s && canFinish(s);
  view.finish.hidden = !s || s.phase === "finishing" || s.phase === "finished" || !owner;
  view.finish.disabled = !finishable || data.busy;
  if (!finishable) resetFinishConfirm(view);
  text(view.conn, CONNECTION[data.connection]);
  view.conn.className = `conn conn-${data.connection}`;
  tick(view);
}

const END = { label: "End round", again: "Click again to end the round" };
const FINISH = { label: "Finish now", again: "Click again to finish the session" };

/**
 * A button that asks for a second click: it reads `label`, or "Click again" while it waits
 * (its accessible name then says what the second click does). Both texts sit in one grid
 * cell, the hidden one as `data-alt`, so the button is as wide in both states.
 */
function twoClick(className: string, words: typeof END, title: string): HTMLButtonElement {
  return h(
    "button",
    { type: "button", class: `${className} two-click`, title, "data-alt": AGAIN, "aria-label": words.label },
    h("span", {}, words.label),
  );
}

function setConfirm(button: HTMLButtonElement, words: typeof END, confirm: boolean): void {
  button.classList.toggle("confirm", confirm);
  text(button.firstElementChild as HTMLElement, confirm ? AGAIN : words.label);
  attr(button, "data-alt", confirm ? words.label : AGAIN);
  attr(button, "aria-label", confirm ? words.again : words.label);
}

function resetConfirm(view: View): void {
  view.confirmUntil = 0;
  setConfirm(view.end, END, false);
}

function resetFinishConfirm(view: View): void {
  view.finishConfirmUntil = 0;
  setConfirm(view.finish, FINISH, false);
}

/**
 * The owner's name on "Annotators" gives way only after the env name (`.meta`) is as short as
 * it goes: the button keeps its width unless the bar, laid out so, still overflows; then it
 * may shrink (the name cut with an ellipsis, whole in the title). Flex shrink factors alone
 * would take a sliver off both, which cuts a name that fits.
 */
function fitPeople(view: View, bar: HTMLElement): void {
  const button = view.people;
  if (!button.classList.contains("shared") || button.hidden) {
    button.classList.remove("squeeze");
    return;
  }
  button.classList.remove("squeeze");
  if (bar.scrollWidth > bar.clientWidth) button.classList.add("squeeze");
}

function tick(view: View): void {
  const s = view.data?.session;
  if (!s) {
    text(view.timer, "");
    return;
  }
  const elapsed = elapsedNow(s.timer, s.phase === "ready" ? Date.now() - view.data!.sessionAt : 0);
  if (s.phase !== "ready") view.timer.classList.remove("late");
  const budget = s.timer.budget_s;
  text(view.timer, budget > 0 ? `${clock(Math.min(elapsed, budget))} / ${clock(budget)}` : clock(elapsed));
  view.timer.classList.toggle("paused", s.timer.paused);
  view.timer.classList.toggle("late", budget > 0 && budget - elapsed < 30 && s.phase === "ready");
  if (view.confirmUntil && Date.now() > view.confirmUntil) resetConfirm(view);
  if (view.finishConfirmUntil && Date.now() > view.finishConfirmUntil) resetFinishConfirm(view);
  if (view.people.classList.contains("shared")) fitPeople(view, view.people.parentElement!);
}

function build(element: HTMLElement): View {
  const meta = h("span", { class: "meta" });
  const round = h("span", { class: "round" });
  const phase = h("span", { class: "phase" });
  const timer = h("span", { class: "timer num", role: "timer", "aria-label": "Round time" });
  const pause = h("button", { type: "button", class: "ghost small" }, "Pause");
  const comparisons = h("span", { class: "num" });
  const pairs = h("span", { class: "num" });
  const end = twoClick(
    "end-round",
    END,
    "End the round now (click twice): the agent learns from your answers, then the next round opens",
  );
  const finish = twoClick(
    "finish-now",
    FINISH,
    "No more rounds after this one (click twice): the agent trains further on your reward model, then you can watch and download it",
  );
  const conn = h("span", { class: "conn", role: "status" });
  const help = h(
    "button",
    { type: "button", class: "help", title: "How to use this page (?)", "aria-label": "Show the guide" },
    "?",
  );
  round.title = ROUND_TITLE;
  const sessions = h("button", { type: "button", class: "brand", title: "Sessions" }, "groupwise");
  const timerWrap = h("span", { class: "timer-wrap" }, timer, pause);
  const badge = h("span", { class: "person-badge", "aria-hidden": "true" });
  const whoName = h("span", { class: "who-name" });
  const who = h("span", { class: "who", hidden: true }, badge, h("span", { class: "sr-only" }, "You are "), whoName);
  const peopleBadge = h("span", { class: "person-badge", "aria-hidden": "true", hidden: true });
  const peopleLabel = h("span", { class: "people-label", "aria-hidden": "true", hidden: true });
  // Two people: share the session.
  const peopleIcon = s(
    "svg",
    { class: "people-icon", viewBox: "0 0 24 24", width: 18, height: 18, "aria-hidden": "true" },
    s("circle", { cx: 9, cy: 8, r: 3.2 }),
    s("path", { d: "M2.5 19c.6-3.6 3.2-5.5 6.5-5.5s5.9 1.9 6.5 5.5" }),
    s("path", { d: "M15.5 5.2a3 3 0 0 1 0 5.6M17.5 13.8c1.6.6 2.8 2 3.2 3.9" }),
  );
  const people = h(
    "button",
    { type: "button", class: "ghost small people-button", "aria-haspopup": "dialog", "aria-label": "Annotators" },
    peopleIcon,
    peopleBadge,
    peopleLabel,
  );
  const counts = h(
    "dl",
    { class: "counts" },
    h("div", {}, h("dt", {}, "Comparisons"), h("dd", {}, comparisons, h("span", { class: "total num" }))),
    h("div", {}, h("dt", {}, "Pairs"), h("dd", {}, pairs, h("span", { class: "total num" }))),
  );
  element.classList.add("statusbar");
  element.replaceChildren(
    sessions,
    meta,
    h("span", { class: "sep", "aria-hidden": "true" }),
    round,
    phase,
    timerWrap,
    counts,
    who,
    people,
    conn,
    end,
    finish,
    help,
  );
  const view: View = {
    meta,
    timerWrap,
    counts,
    round,
    phase,
    timer,
    pause,
    comparisons,
    pairs,
    end,
    finish,
    conn,
    help,
    brand: sessions,
    who,
    badge,
    whoName,
    people,
    peopleIcon,
    peopleBadge,
    peopleLabel,
    data: null,
    handlers: null,
    confirmUntil: 0,
    finishConfirmUntil: 0,
  };
  pause.addEventListener("click", () => {
    if (view.data?.session?.timer.paused) view.handlers?.resume();
    else view.handlers?.pause();
  });
  end.addEventListener("click", () => {
    if (view.confirmUntil > Date.now()) {
      resetConfirm(view);
      view.handlers?.endRound();
      return;
    }
    view.confirmUntil = Date.now() + CONFIRM_MS;
    setConfirm(end, END, true);
  });
  finish.addEventListener("click", () => {
    if (view.finishConfirmUntil > Date.now()) {
      resetFinishConfirm(view);
      view.handlers?.finish();
      return;
    }
    view.finishConfirmUntil = Date.now() + CONFIRM_MS;
    setConfirm(finish, FINISH, true);
  });
  sessions.addEventListener("click", () => view.handlers?.sessions());
  help.addEventListener("click", () => view.handlers?.guide());
  people.addEventListener("click", () => view.handlers?.people());
  window.setInterval(() => tick(view), 500);
  return view;
}
