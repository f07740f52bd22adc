/**
 * The progress panel over the comparison area while the round is not open: the worker's
 * phase and percentage while it prepares or retrains (from SSE `state` events), the end of
 * the session, or the failure with its reason and a retry.
 */
import type { SessionState } from "../api";
import { phaseName, roundOf } from "../lib/format";
import { h, memo, text } from "./dom";

export interface ProgressData {
  session: SessionState | null;
  exportUrl: string | null;
  busy: boolean;
  /** Whether this page is the session's owner: only they retry a failed step (issue 21). */
  owner?: boolean;
}

export interface ProgressHandlers {
  retry(): void;
}

interface View {
  title: HTMLElement;
  step: HTMLElement;
  bar: HTMLElement;
  fill: HTMLElement;
  percent: HTMLElement;
  message: HTMLElement;
  note: HTMLElement;
  retry: HTMLButtonElement;
  exportLink: HTMLAnchorElement;
  handlers: ProgressHandlers | null;
}

const views = new WeakMap<Element, View>();

export function renderProgress(element: HTMLElement, data: ProgressData, handlers: ProgressHandlers): void {
  const view = memo(views, element, () => build(element));
  view.handlers = handlers;
  const s = data.session;
  const phase = s?.phase;
  element.hidden = !s || phase === "ready";
  if (!s || phase === "ready") return;
  element.dataset.phase = phase;
  const p = s.progress;
  const round = Math.min(s.round, s.rounds - 1);
  const fraction = Math.max(0, Math.min(1, p?.fraction ?? 0));
  const showBar = phase === "preparing" || phase === "training" || phase === "finishing";
  view.bar.hidden = !showBar;
  view.step.parentElement!.hidden = !showBar;
  view.message.hidden = !showBar;
  view.retry.hidden = phase !== "failed" || data.owner === false;
  view.retry.disabled = data.busy;
  view.exportLink.hidden = phase !== "finished" || !data.exportUrl;
  if (data.exportUrl) view.exportLink.href = data.exportUrl;
  switch (phase) {
    case "preparing":
      text(view.title, `Preparing round ${roundOf(round, s.rounds)}`);
      text(view.note, "The new behaviours appear here by themselves when they are ready.");
      break;
    case "training":
      text(view.title, `Round ${round} ended: learning from your answers`);
      text(view.note, "The reward model and the agent train now; the next round starts by itself.");
      break;
    case "finishing":
      text(view.title, "Final training on your reward model");
      text(
        view.note,
        "No more questions: the agent trains further on the reward model learned from your " +
          "answers, now frozen. Its video and the download appear here next.",
      );
      break;
    case "finished":
      text(view.title, "Session finished");
      text(
        view.note,
        `${s.counts.comparisons_total} comparisons and ${s.counts.pairs_total} preference pairs over ` +
          `${s.rounds === 1 ? "1 round (round 0)" : `${s.rounds} rounds (0–${s.rounds - 1})`}. Thank you.`,
      );
      break;
    case "failed":
      text(view.title, failedTitle(s.failed_phase ?? null, round, s.rounds));
      text(view.note, s.error ?? "The worker failed without a message; see the server log.");
      break;
  }
  text(view.step, showBar && p ? phaseName(p.phase) : "");
  text(view.message, showBar && p?.message ? p.message : "");
  const pct = Math.round(fraction * 100);
  text(view.percent, showBar ? `${pct}%` : "");
  view.fill.style.width = `${pct}%`;
  view.bar.setAttribute("aria-valuenow", String(pct));
  view.bar.setAttribute("aria-valuetext", `${p ? phaseName(p.phase) : "working"}: ${pct}%`);
}

/**
 * What failed, in the words of the step (issue 23: every failure read "The training worker
 * stopped", also when the worker raised and went on); the note under it gives the error,
 * "the training worker stopped (exit code …)" when its process died.
 */
export function failedTitle(step: string | null, round: number, rounds: number): string {
  switch (step) {
    case "preparing":
      return `Round ${roundOf(round, rounds)} could not be prepared`;
    case "training":
      return `Training after round ${round} failed`;
    case "finishing":
      return "The final training failed";
    default:
      return "The training worker stopped";
  }
}

function build(element: HTMLElement): View {
  const title = h("h2", { class: "progress-title" });
  const step = h("span", { class: "progress-step" });
  const percent = h("span", { class: "progress-percent num" });
  const fill = h("div", { class: "progress-fill" });
  const bar = h(
    "div",
    { class: "progress-bar", role: "progressbar", "aria-valuemin": 0, "aria-valuemax": 100, "aria-label": "Progress" },
    fill,
  );
  const message = h("p", { class: "progress-message num" });
  const note = h("p", { class: "progress-note" });
  const retry = h("button", { type: "button", class: "primary" }, "Retry");
  const exportLink = h("a", { class: "button", download: "" }, "Download judgements (JSONL)");
  element.classList.add("progress-overlay");
  element.setAttribute("role", "status");
  element.setAttribute("aria-live", "polite");
  element.replaceChildren(
    h(
      "div",
      { class: "progress-card" },
      title,
      h("div", { class: "progress-line" }, step, percent),
      bar,
      message,
      note,
      h("div", { class: "progress-actions" }, retry, exportLink),
    ),
  );
  const view: View = { title, step, bar, fill, percent, message, note, retry, exportLink, handlers: null };
  retry.addEventListener("click", () => view.handlers?.retry());
  return view;
}
