/**
 * The guide: a few lines on what to do, shown over the page the first time a mode is opened
 * in this browser and again from the status bar's "?" (or the ? key). A modal dialog: the
 * page behind is inert and Tab cycles through the guide's own buttons while it is open (the
 * answer keys rest too); Escape, "Got it" or a click beside it closes it, and the focus goes
 * back where it was.
 */
import { trapStep } from "../lib/focus";
import { question } from "../lib/format";
import { h, kbd, memo } from "./dom";

export type GuideMode = "groupwise" | "pairwise";

export interface GuideHandlers {
  close(): void;
}

interface View {
  box: HTMLElement;
  body: HTMLElement;
  ok: HTMLButtonElement;
  mode: GuideMode | null;
  open: boolean;
  handlers: GuideHandlers | null;
  /** What had the focus before the guide opened (it gets it back). */
  before: Element | null;
}

const views = new WeakMap<Element, View>();

type Line = Array<Node | string>;

/** A key named in a sentence (read out, unlike the hints' `kbd`). */
const key = (name: string): HTMLElement => h("span", { class: "keys" }, h("kbd", {}, name));

/** The guide's lines per mode: what the page shows and what each interaction does. */
function lines(mode: GuideMode): Line[] {
  if (mode === "pairwise") {
    return [
      ["Two clips play side by side; each is a short behaviour of the agent."],
      [h("strong", {}, question("clip"))],
      [kbd("←", "A"), " left · ", kbd("→", "D"), " right · ", kbd("↑", "W"), " about equal · ", kbd("↓", "S"), " skip this pair"],
      [kbd("U"), " undoes your last answer. The round ends after its time or its comparisons, or when you press End round twice (the second click confirms); then the agent learns from your answers."],
    ];
  }
  return [
    [
      "Each arc of the chart is a behaviour of the agent (inner ring) or a cluster of similar " +
        "behaviours (outer rings, its size on it). Hover an arc to watch it.",
    ],
    [
      h("strong", {}, "Click"),
      " an arc to put its behaviours in group A, ",
      h("strong", {}, "Shift-click"),
      " to add them, ",
      h("strong", {}, "right-click"),
      " (or Alt-click) to fill group B. ",
      kbd("G"),
      " switches the group that clicks fill.",
    ],
    [
      h("strong", {}, "Click a cluster of more than 8"),
      " to make it the chart's centre: its behaviours get the whole ring. The breadcrumb over " +
        "the chart or ",
      key("Esc"),
      " goes back out; the wheel or a pinch zooms.",
    ],
    [
      "To take one behaviour out of its group, ",
      h("strong", {}, "Shift-click"),
      " it or press × on its clip. Clicking what a group holds already changes nothing.",
    ],
    [
      "By keyboard: Tab into the chart, ",
      key("Shift"),
      " + arrows move between arcs, ",
      key("Enter"),
      " fills the group, ",
      key("Alt"),
      " + ",
      key("Enter"),
      " the other, ",
      key("C"),
      " centres on a cluster.",
    ],
    [kbd("N"), " shows the next suggested comparison instead of choosing groups yourself."],
    [h("strong", {}, question("group"))],
    [kbd("←", "A"), " group A · ", kbd("→", "D"), " group B · ", kbd("↑", "W"), " about equal · ", kbd("U"), " undo the last answer"],
    ["The round ends after its time or its comparisons, or when you press End round twice (the second click confirms); then the agent learns from your answers."],
  ];
}

export function renderGuide(element: HTMLElement, mode: GuideMode | null, open: boolean, handlers: GuideHandlers): void {
  const view = memo(views, element, () => build(element));
  view.handlers = handlers;
  const show = open && mode !== null;
  if (mode !== null && mode !== view.mode) {
    view.mode = mode;
    view.body.replaceChildren(...lines(mode).map((line) => h("li", {}, ...line)));
  }
  if (show === view.open) return;
  view.open = show;
  element.hidden = !show;
  // The page behind can be neither focused nor clicked while the guide is open.
  for (const sibling of element.parentElement?.children ?? []) {
    if (sibling !== element) sibling.toggleAttribute("inert", show);
  }
  if (show) {
    view.before = document.activeElement;
    view.ok.focus();
  } else if (view.before instanceof HTMLElement && view.before.isConnected) {
    view.before.focus();
  }
}

/** Tab and Shift+Tab go round the guide's controls (issue 23: Tab from "Got it" reached the
 * page behind). */
function trapTab(view: View, e: KeyboardEvent): void {
  if (!view.open || e.key !== "Tab" || e.altKey || e.ctrlKey || e.metaKey) return;
  const controls = [...view.box.querySelectorAll<HTMLElement>("button, [href], input, select, [tabindex]")].filter(
    (el) => !el.hasAttribute("disabled") && el.tabIndex >= 0,
  );
  const next = controls[trapStep(controls.indexOf(document.activeElement as HTMLElement), controls.length, e.shiftKey)];
  e.preventDefault();
  next?.focus();
}

function build(element: HTMLElement): View {
  const body = h("ul", { class: "guide-lines" });
  const ok = h("button", { type: "button", class: "primary" }, "Got it");
  const close = h("button", { type: "button", class: "ghost close", "aria-label": "Close the guide" }, "×");
  const box = h(
    "section",
    { class: "guide", role: "dialog", "aria-modal": "true", "aria-labelledby": "guide-title" },
    h("header", { class: "guide-head" }, h("h2", { id: "guide-title" }, "How this page works"), close),
    body,
    h(
      "footer",
      { class: "guide-foot" },
      h("span", { class: "muted" }, "The ", h("strong", {}, "?"), " button in the top bar shows this again."),
      ok,
    ),
  );
  element.classList.add("guide-backdrop");
  element.hidden = true;
  element.replaceChildren(box);
  const view: View = { box, body, ok, mode: null, open: false, handlers: null, before: null };
  ok.addEventListener("click", () => view.handlers?.close());
  close.addEventListener("click", () => view.handlers?.close());
  element.addEventListener("click", (e) => {
    if (e.target === element) view.handlers?.close();
  });
  document.addEventListener("keydown", (e) => trapTab(view, e), true);
  return view;
}
