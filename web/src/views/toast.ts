/**
 * Confirmations and error messages: one at a time, in the message bar under the workspace
 * (a strip of their own, so they never cover a control); errors are announced at once,
 * confirmations politely.
 */
import type { Toast } from "../state";
import { h, memo, text } from "./dom";

export interface ToastHandlers {
  dismiss(id: number): void;
  undo(): void;
}

interface View {
  box: HTMLElement;
  message: HTMLElement;
  undo: HTMLButtonElement;
  close: HTMLButtonElement;
  shown: number | null;
  timer: number | undefined;
  handlers: ToastHandlers | null;
}

const views = new WeakMap<Element, View>();
const OK_MS = 5000;
const INFO_MS = 6000;

export function renderToast(element: HTMLElement, toast: Toast | null, canUndo: boolean, handlers: ToastHandlers): void {
  const view = memo(views, element, () => build(element));
  view.handlers = handlers;
  view.box.hidden = !toast;
  view.undo.hidden = !toast?.undo || !canUndo;
  if (!toast || toast.id === view.shown) return;
  view.shown = toast.id;
  view.box.className = `toast toast-${toast.kind}`;
  // Errors are alerts (read at once); confirmations are polite.
  view.box.setAttribute("role", toast.kind === "error" ? "alert" : "status");
  text(view.message, toast.text);
  view.message.title = toast.text; // the bar shows two lines; the whole text on hover
  window.clearTimeout(view.timer);
  if (toast.kind !== "error") {
    const id = toast.id;
    view.timer = window.setTimeout(() => view.handlers?.dismiss(id), toast.kind === "ok" ? OK_MS : INFO_MS);
  }
}

function build(element: HTMLElement): View {
  const message = h("span", { class: "toast-message" });
  const undo = h("button", { type: "button", class: "link" }, "Undo");
  const close = h("button", { type: "button", class: "link close", "aria-label": "Dismiss message" }, "×");
  const box = h("div", { class: "toast", hidden: true }, message, undo, close);
  element.replaceChildren(box);
  const view: View = { box, message, undo, close, shown: null, timer: undefined, handlers: null };
  undo.addEventListener("click", () => view.handlers?.undo());
  close.addEventListener("click", () => view.shown !== null && view.handlers?.dismiss(view.shown));
  return view;
}
