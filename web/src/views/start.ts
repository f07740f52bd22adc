/**
 * The start screen, shown when the URL names no session and the server has none yet (or the
 * person asks for the list): open an existing session or create one.
 */
import type { SessionCreate, SessionState, Settings } from "../api";
import { h, memo, text } from "./dom";
import { roundText } from "./status";

export interface StartData {
  envs: string[];
  sessions: SessionState[];
  busy: boolean;
}

export interface StartHandlers {
  open(sid: string): void;
  create(body: SessionCreate): void;
}

interface View {
  env: HTMLSelectElement;
  list: HTMLElement;
  listBox: HTMLElement;
  submit: HTMLButtonElement;
  handlers: StartHandlers | null;
  sessions: SessionState[] | null;
  envs: string[] | null;
}

const views = new WeakMap<Element, View>();

/** The settings the form shows: the numeric ones. */
type NumericSetting = { [K in keyof Settings]-?: Settings[K] extends number | undefined ? K : never }[keyof Settings];

const FIELDS: Array<[NumericSetting, string, number, number]> = [
  ["pool_size", "Behaviours per round", 8, 200],
  ["rounds", "Rounds", 1, 100],
  ["round_seconds", "Seconds per round (0: no limit)", 0, 86400],
  ["comparisons_per_round", "Comparisons per round (0: no limit)", 0, 10000],
];

export function renderStart(element: HTMLElement, data: StartData, handlers: StartHandlers): void {
  const view = memo(views, element, () => build(element));
  view.handlers = handlers;
  view.submit.disabled = data.busy || data.envs.length === 0;
  if (view.envs !== data.envs) {
    view.envs = data.envs;
    view.env.replaceChildren(...data.envs.map((e) => h("option", { value: e }, e)));
  }
  if (view.sessions !== data.sessions) {
    view.sessions = data.sessions;
    view.listBox.hidden = data.sessions.length === 0;
    view.list.replaceChildren(
      ...data.sessions.map((s) => {
        const open = h("button", { type: "button", class: "small" }, "Open");
        open.setAttribute("aria-label", `Open session ${s.id}`);
        open.addEventListener("click", () => view.handlers?.open(s.id));
        return h(
          "li",
          {},
          h("span", { class: "num" }, s.id),
          h("span", {}, `${s.env} · ${s.mode}`),
          h("span", {}, `${roundText(s)} · ${s.phase}`),
          h("span", { class: "num muted" }, `${s.counts.comparisons_total} comparisons`),
          open,
        );
      }),
    );
  }
}

function build(element: HTMLElement): View {
  const env = h("select", { name: "env", id: "start-env" });
  const mode = h(
    "fieldset",
    { class: "modes" },
    h("legend", {}, "Interface"),
    h("label", {}, h("input", { type: "radio", name: "mode", value: "groupwise", checked: true }), " Groupwise (explore and compare groups)"),
    h("label", {}, h("input", { type: "radio", name: "mode", value: "pairwise" }), " Pairwise baseline (two clips at a time)"),
  );
  const settings = h("details", { class: "settings" }, h("summary", {}, "Settings"));
  for (const [key, label, min, max] of FIELDS) {
    settings.append(
      h("label", {}, h("span", {}, label), h("input", { type: "number", name: key, min, max, placeholder: "default" })),
    );
  }
  const submit = h("button", { type: "submit", class: "primary" }, "Start session");
  const form = h(
    "form",
    { class: "start-form", "aria-labelledby": "start-title" },
    h("h2", { id: "start-title" }, "New session"),
    h("label", { for: "start-env" }, "Environment"),
    env,
    mode,
    settings,
    submit,
  );
  const list = h("ul", { class: "session-list" });
  const listBox = h("section", { class: "sessions", "aria-labelledby": "sessions-title" }, h("h2", { id: "sessions-title" }, "Sessions"), list);
  element.classList.add("start");
  element.replaceChildren(
    h(
      "div",
      { class: "start-inner" },
      h("h1", {}, "groupwise"),
      h("p", { class: "lede" }, "Teach an agent by comparing groups of its behaviours."),
      form,
      listBox,
    ),
  );
  const view: View = { env, list, listBox, submit, handlers: null, sessions: null, envs: null };
  form.addEventListener("submit", (e) => {
    e.preventDefault();
    const fd = new FormData(form);
    const body: SessionCreate = {
      env: String(fd.get("env") ?? ""),
      mode: fd.get("mode") === "pairwise" ? "pairwise" : "groupwise",
    };
    const chosen: Partial<Pick<Settings, NumericSetting>> = {};
    for (const [key] of FIELDS) {
      const v = String(fd.get(key) ?? "").trim();
      if (v !== "") chosen[key] = Number(v);
    }
    if (Object.keys(chosen).length) body.settings = chosen;
    view.handlers?.create(body);
  });
  text(submit, "Start session");
  return view;
}
