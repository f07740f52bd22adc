/**
 * The start screen, shown when the URL names no session (or `?new`), the server has none
 * yet, or the person asks for the list: open an existing session or create one.
 *
 * The New-session form offers every session setting the server's schema has
 * (`lib/settings-form`), each filled with what the server would store for the chosen env
 * (`POST /api/settings/resolve`, asked again after every change). Only the fields the person
 * changed are sent; the server fills the rest exactly as the form shows them.
 */
import type { EnvInfo, SessionCreate, SessionState, Settings } from "../api";
import { OTHER_ENV, envAbout, envOptionText } from "../lib/env-choice";
import {
  MODE_HELP,
  type Schemas,
  type SettingField,
  chosenSettings,
  helpIn,
  inputText,
  refusalText,
  settingFields,
  touch,
  valueAt,
} from "../lib/settings-form";
import type { NewSessionState } from "../state";
import { attr, h, memo, text } from "./dom";
import { roundText } from "./status";

export interface StartData {
  envs: EnvInfo[];
  schemas: Schemas | null;
  newSession: NewSessionState;
  sessions: SessionState[];
  busy: boolean;
}

export interface StartHandlers {
  open(sid: string): void;
  /** Ask what a session of this body would store (answers arrive as `newSession`). */
  check(body: SessionCreate): void;
  create(body: SessionCreate): void;
}

type Control = HTMLInputElement | HTMLSelectElement;

interface View {
  element: HTMLElement;
  form: HTMLFormElement;
  env: HTMLSelectElement;
  gymId: HTMLInputElement;
  envAbout: HTMLElement;
  envError: HTMLElement;
  groups: { feedback: HTMLElement; training: HTMLElement; advanced: HTMLElement };
  formError: HTMLElement;
  list: HTMLElement;
  listBox: HTMLElement;
  submit: HTMLButtonElement;
  handlers: StartHandlers | null;
  sessions: SessionState[] | null;
  envs: EnvInfo[] | null;
  schemas: Schemas | null;
  fields: SettingField[];
  controls: Map<string, Control>;
  /** Fields the person changed: sent as chosen; the others show the server's values. */
  touched: Set<string>;
  /** Inputs that mean no value (checked here, before asking the server). */
  localErrors: string[];
  timer: ReturnType<typeof setTimeout> | null;
  data: StartData | null;
}

const views = new WeakMap<Element, View>();
/** Wait after a keystroke before asking the server (ms). */
const CHECK_DELAY_MS = 350;

export function renderStart(element: HTMLElement, data: StartData, handlers: StartHandlers): void {
  const view = memo(views, element, () => build(element));
  view.handlers = handlers;
  view.data = data;
  if (view.envs !== data.envs) {
    view.envs = data.envs;
    fillEnvs(view, data.envs);
  }
  if (view.schemas !== data.schemas && data.schemas) {
    view.schemas = data.schemas;
    buildFields(view, data.schemas);
  }
  const { resolved, envError, error } = data.newSession;
  if (resolved) showResolved(view, resolved);
  const other = view.env.value === OTHER_ENV;
  view.gymId.hidden = !other;
  text(view.envAbout, envAbout(other ? null : (data.envs.find((e) => e.name === view.env.value) ?? null)));
  text(view.envError, envError ?? "");
  view.envError.hidden = !envError;
  attr(view.env, "aria-invalid", envError && !other ? "true" : null);
  attr(view.gymId, "aria-invalid", envError && other ? "true" : null);
  const formError = view.localErrors.length ? view.localErrors.join(" ") : error && refusalText(error, view.fields);
  text(view.formError, formError ?? "");
  view.formError.hidden = !formError;
  view.submit.disabled =
    data.busy || !envName(view) || Boolean(envError) || view.localErrors.length > 0 || !data.schemas;
  if (view.sessions !== data.sessions) {
    view.sessions = data.sessions;
    renderSessions(view, data.sessions);
  }
}

function envName(view: View): string {
  return (view.env.value === OTHER_ENV ? view.gymId.value : view.env.value).trim();
}

function fillEnvs(view: View, envs: EnvInfo[]): void {
  const before = view.env.value;
  const option = (e: EnvInfo) => h("option", { value: e.name }, envOptionText(e));
  view.env.replaceChildren(
    h("optgroup", { label: "Environments" }, ...envs.filter((e) => e.kind === "env").map(option)),
    h("optgroup", { label: "Case studies (reward-free targets)" }, ...envs.filter((e) => e.kind === "target").map(option)),
    h("option", { value: OTHER_ENV }, "Another Gymnasium id…"),
  );
  if (before && envs.some((e) => e.name === before)) view.env.value = before;
  else if (envs[0]) view.env.value = envs[0].name;
  if (envs.length) check(view);
}

function buildFields(view: View, schemas: Schemas): void {
  view.fields = settingFields(schemas);
  view.controls.clear();
  const sections = new Map<string, HTMLElement>();
  for (const box of Object.values(view.groups)) box.replaceChildren();
  for (const f of view.fields) {
    const row = fieldRow(view, f);
    if (f.group !== "advanced") {
      view.groups[f.group].append(row);
      continue;
    }
    let section = sections.get(f.section);
    if (!section) {
      section = h("fieldset", { class: "setting-group" }, h("legend", {}, f.section));
      sections.set(f.section, section);
      view.groups.advanced.append(section);
    }
    section.append(row);
  }
  if (view.data?.newSession.resolved) showResolved(view, view.data.newSession.resolved);
}

function fieldRow(view: View, f: SettingField): HTMLElement {
  const id = `setting-${f.key.replace(/\W/g, "-")}`;
  let control: Control;
  if (f.kind === "choice") {
    control = h("select", { id, name: f.key }, ...(f.choices ?? []).map((c) => h("option", { value: c }, c)));
  } else if (f.kind === "boolean") {
    control = h("input", { id, name: f.key, type: "checkbox" });
  } else if (f.kind === "integer" || f.kind === "number") {
    control = h("input", { id, name: f.key, type: "number", min: f.min, max: f.max, step: f.step, inputmode: f.kind === "integer" ? "numeric" : "decimal" });
    if (f.nullable) control.placeholder = "default";
  } else {
    control = h("input", { id, name: f.key, type: "text", spellcheck: false });
    if (f.kind === "list") control.placeholder = "e.g. 64, 64";
  }
  view.controls.set(f.key, control);
  const shown = f.help || MODE_HELP[f.key] || f.choiceHelp;
  const help = shown ? h("small", { class: "help", id: `${id}-help` }, helpIn(f, modeOf(view), control.value)) : null;
  if (help) control.setAttribute("aria-describedby", help.id);
  const edited = (now: boolean) => {
    view.touched = touch(view.touched, f.key);
    check(view, now);
  };
  control.addEventListener("input", () => edited(false));
  control.addEventListener("change", () => edited(true));
  return h("div", { class: `setting ${f.kind}` }, h("label", { for: id }, f.label), control, help);
}

/** The training mode the form holds now ("continuous", the default, before it is known). */
function modeOf(view: View): string {
  const control = view.controls.get("training");
  return control?.value || "continuous";
}

/** Each mode-dependent setting's help for the mode chosen now (`MODE_HELP`), and each
 * choice's with help of its own for the choice made (the recipe's measured success). */
function showModeHelp(view: View): void {
  const mode = modeOf(view);
  for (const f of view.fields) {
    if (!MODE_HELP[f.key] && !f.choiceHelp) continue;
    const help = view.form.querySelector(`#setting-${f.key.replace(/\W/g, "-")}-help`);
    if (help) text(help as HTMLElement, helpIn(f, mode, view.controls.get(f.key)?.value));
  }
}

function controlText(control: Control): string {
  return control instanceof HTMLInputElement && control.type === "checkbox" ? String(control.checked) : control.value;
}

function showResolved(view: View, resolved: Settings): void {
  for (const f of view.fields) {
    if (view.touched.has(f.key)) continue;
    const control = view.controls.get(f.key);
    if (!control) continue;
    const value = valueAt(resolved, f.path);
    if (control instanceof HTMLInputElement && control.type === "checkbox") control.checked = value === true;
    else if (control.value !== inputText(value)) control.value = inputText(value);
  }  showModeHelp(view);
}

/** The body the form means now (env, mode, the touched settings); notes inputs that mean no value. */
function body(view: View): SessionCreate {
  const inputs: Record<string, string> = {};
  for (const [key, control] of view.controls) inputs[key] = controlText(control);
  const chosen = chosenSettings(view.fields, inputs, view.touched);
  view.localErrors = chosen.errors;
  const mode = new FormData(view.form).get("mode") === "pairwise" ? "pairwise" : "groupwise";
  const out: SessionCreate = { env: envName(view), mode };
  if (Object.keys(chosen.settings).length) out.settings = chosen.settings as Partial<Settings>;
  return out;
}

/** Ask the server what the form means, now or after a pause in typing. */
function check(view: View, now = true): void {
  showModeHelp(view);
  if (view.timer) clearTimeout(view.timer);
  view.timer = null;
  const run = () => {
    view.timer = null;
    const b = body(view);
    if (view.data && view.handlers) renderStart(view.element, view.data, view.handlers); // local errors
    if (b.env && view.localErrors.length === 0) view.handlers?.check(b);
  };
  if (now) run();
  else view.timer = setTimeout(run, CHECK_DELAY_MS);
}

function renderSessions(view: View, sessions: SessionState[]): void {
  view.listBox.hidden = sessions.length === 0;
  view.list.replaceChildren(
    ...sessions.map((s) => {
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

function build(element: HTMLElement): View {
  const env = h("select", { name: "env", id: "start-env", "aria-describedby": "start-env-about start-env-error" });
  const gymId = h("input", {
    type: "text",
    id: "start-gym-id",
    "aria-label": "Gymnasium id",
    "aria-describedby": "start-env-about start-env-error",
    placeholder: "e.g. Pendulum-v1",
    spellcheck: false,
    autocomplete: "off",
    hidden: true,
  });
  const about = h("p", { class: "env-about", id: "start-env-about" });
  const envError = h("p", { class: "field-error", id: "start-env-error", role: "alert", hidden: true });
  const mode = h(
    "fieldset",
    { class: "modes" },
    h("legend", {}, "Interface"),
    h("label", {}, h("input", { type: "radio", name: "mode", value: "groupwise", checked: true }), " Groupwise (explore and compare groups)"),
    h("label", {}, h("input", { type: "radio", name: "mode", value: "pairwise" }), " Pairwise baseline (two clips at a time)"),
  );
  const feedback = h("div", { class: "setting-list" });
  const training = h("div", { class: "setting-list" });
  const advanced = h("div", { class: "advanced-sections" });
  const formError = h("p", { class: "field-error", id: "start-form-error", role: "alert", hidden: true });
  const submit = h("button", { type: "submit", class: "primary" }, "Start session");
  const form = h(
    "form",
    { class: "start-form", "aria-labelledby": "start-title" },
    h("div", { class: "form-head" }, h("h2", { id: "start-title" }, "New session"), formError, submit),
    h(
      "div",
      { class: "env-row" },
      h("label", { for: "start-env" }, "Environment"),
      h("div", { class: "env-choice" }, env, gymId),
      about,
      envError,
    ),
    h(
      "div",
      { class: "setting-groups" },
      h("fieldset", { class: "setting-group" }, h("legend", {}, "Feedback"), mode, feedback),
      h("fieldset", { class: "setting-group" }, h("legend", {}, "Training"), training),
    ),
    h("details", { class: "advanced" }, h("summary", {}, "Advanced: clips, the worker and shared sessions"), advanced),
  );
  const list = h("ul", { class: "session-list" });
  const listBox = h("section", { class: "sessions", "aria-labelledby": "sessions-title" }, h("h2", { id: "sessions-title" }, "Sessions"), list);
  element.classList.add("start");
  element.replaceChildren(
    h(
      "div",
      { class: "start-inner" },
      h("div", { class: "start-head" }, h("h1", {}, "groupwise"), h("p", { class: "lede" }, "Teach an agent by comparing groups of its behaviours.")),
      form,
      listBox,
    ),
  );
  const view: View = {
    element,
    form,
    env,
    gymId,
    envAbout: about,
    envError,
    groups: { feedback, training, advanced },
    formError,
    list,
    listBox,
    submit,
    handlers: null,
    sessions: null,
    envs: null,
    schemas: null,
    fields: [],
    controls: new Map(),
    touched: new Set(),
    localErrors: [],
    timer: null,
    data: null,
  };
  env.addEventListener("change", () => {
    if (env.value === OTHER_ENV) {
      gymId.hidden = false;
      gymId.focus();
    }
    check(view);
  });
  gymId.addEventListener("input", () => check(view, false));
  gymId.addEventListener("change", () => check(view));
  form.addEventListener("submit", (e) => {
    e.preventDefault();
    if (!form.reportValidity()) return;
    const b = body(view);
    if (!b.env || view.localErrors.length) return check(view);
    view.handlers?.create(b);
  });
  return view;
}
