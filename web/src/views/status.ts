/**
 * The status bar: session, round and phase, the round's timer (pause / resume), counters of
 * comparisons and preference pairs (this round and in total), "End round" and "Finish now"
 * (each asks for a second click: "Click again"), and "?" (the guide).
 *
 * One line at 1366 px whatever it says (docs/app.md, "Front end"): only the env name gives
 * way, cut with an ellipsis (the full name in its title), and a two-click button is as wide
 * in both its texts. Once the session is finishing or finished, the round's timer, counters
 * and "End round" are gone.
 */
import type { SessionState } from "../api";
import { clock, elapsedNow, roundOf } from "../lib/format";
import type { State } from "../state";
import { attr, h, memo, text } from "./dom";

export interface StatusData {
  session: SessionState | null;
  sessionAt: number;
  connection: State["connection"];
  /** A control request (pause, end round…) is in flight. */
  busy: boolean;
}

export interface StatusHandlers {
  pause(): void;
  resume(): void;
  endRound(): void;
  /** No more rounds after this one: the final phase, then the agent. */
  finish(): void;
  sessions(): void;
  guide(): void;
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
  view.timerWrap.hidden = over;
  view.counts.hidden = over;
  view.end.hidden = over;
  const ready = s?.phase === "ready";
  view.pause.disabled = !ready || data.busy;
  const paused = s?.timer.paused ?? false;
  text(view.pause, paused ? "Resume" : "Pause");
  attr(view.pause, "aria-label", paused ? "Resume the round timer" : "Pause the round timer");
  view.end.disabled = !ready || data.busy;
  if (!ready) resetConfirm(view);
  const finishable = !!s && canFinish(s);
  view.finish.hidden = !s || s.phase === "finishing" || s.phase === "finished";
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
  window.setInterval(() => tick(view), 500);
  return view;
}
