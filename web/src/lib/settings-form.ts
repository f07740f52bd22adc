/**
 * The New-session form's fields, from the server's OpenAPI schema (docs/app.md, "New
 * session"): every `SessionSettings` field, its bounds, its label and help text, grouped.
 * A setting the server adds appears here by itself (in Advanced unless it is named below).
 *
 * Pure: schema in, field descriptors out; input texts in, the chosen settings out.
 */

/** The parts of a JSON Schema (as FastAPI writes it) that the form reads. */
export interface JsonSchema {
  type?: string;
  title?: string;
  description?: string;
  enum?: unknown[];
  anyOf?: JsonSchema[];
  $ref?: string;
  minimum?: number;
  maximum?: number;
  exclusiveMinimum?: number;
  exclusiveMaximum?: number;
  multipleOf?: number;
  items?: JsonSchema;
  prefixItems?: JsonSchema[];
  properties?: Record<string, JsonSchema>;
  /** One line per choice of a choice field, shown when it is chosen (the recipes' measured
   * success: `SessionSettings.recipe`). */
  "x-choice-help"?: Record<string, string>;
}

export type Schemas = Record<string, JsonSchema>;

export type FieldKind = "integer" | "number" | "boolean" | "choice" | "text" | "list";
export type GroupId = "feedback" | "training" | "advanced";

export interface SettingField {
  /** Where the value sits in the settings: ["pool_size"], ["ppo", "batch_size"]. */
  path: readonly string[];
  /** The path joined by dots: the input's name. */
  key: string;
  label: string;
  /** The schema's description, for people ("" when it has none). */
  help: string;
  kind: FieldKind;
  /** An empty input means null (the server's default). */
  nullable: boolean;
  choices?: string[];
  /** Of a choice: the help each choice shows when chosen (the schema's `x-choice-help`). */
  choiceHelp?: Record<string, string>;
  /** Of a list: whether its items are whole numbers. */
  integerItems?: boolean;
  min?: number;
  max?: number;
  /** The input's step: 1 (or the multiple) for whole numbers, "any" otherwise. */
  step?: number | "any";
  group: GroupId;
  /** The Advanced subsection: "Session", or the nested config's title ("PPO", "Reward model"). */
  section: string;
}

/** The schema's name of the settings object. */
export const SETTINGS_SCHEMA = "SessionSettings";

/** Shown first, in this order, in their groups; every other setting goes to Advanced. */
export const GROUPS: Readonly<Record<Exclude<GroupId, "advanced">, readonly string[]>> = {
  feedback: [
    "comparisons_per_round",
    "rounds",
    "round_seconds",
    "pool_size",
    "clip_seconds",
    "fragment_length",
    "pair_derivation",
  ],
  training: [
    "training",
    "ppo_steps_per_round",
    "final_steps",
    // the recipe, then its parts, each changeable on its own (issue 39)
    "recipe",
    "ppo_preset",
    "pretrain_steps",
    "pool_variants",
    "reward_inputs",
    "exploration_fraction",
    "teach_log_std",
    "seed",
    "eval_episodes",
  ],
};

/** Settings the page never offers: a session made here is driven by the app's worker
 * (`driver: "library"` is for a program's `groupwise.WebTeacher`), and `research` (a
 * partial run config) is for programs and tests. */
export const HIDDEN: ReadonlySet<string> = new Set(["driver", "research"]);

/** Pairs of settings that say the same thing two ways: choosing one lets the server derive
 * the other (L in steps from simulated seconds, or the reverse). */
export const COUPLED: ReadonlyArray<readonly [string, string]> = [["clip_seconds", "fragment_length"]];

const SECTION_NAMES: Record<string, string> = { ppo: "PPO", reward: "Reward model" };
const WORDS: Record<string, string> = { ppo: "PPO", gae: "GAE", l2: "L2", lr: "LR", obs: "obs" };

/** "Ppo Steps Per Round" → "PPO steps per round". */
export function labelOf(title: string): string {
  const words = title.split(/[\s_]+/).filter(Boolean).map((w) => WORDS[w.toLowerCase()] ?? w.toLowerCase());
  const text = words.join(" ");
  return text.charAt(0).toUpperCase() + text.slice(1);
}

/**
 * A description as the page says it: its first sentence (the config's docstrings go on with
 * the reasons, for developers), "null" is an empty field, names are words. A colon does not
 * end it (issue 39: "continuous: the agent trains while you compare; …" read "continuous:").
 */
export function helpOf(description: string | undefined): string {
  const text = (description ?? "").replace(/\s+/g, " ").trim();
  const first = text.match(/^.*?[.;](?=\s+[A-Z(]|$)/)?.[0] ?? text;
  return first.replace(/\bnull\b/g, "empty").replace(/([a-z])_(?=[a-z])/g, "$1 ");
}

/** The two training modes (`SessionSettings.training`). */
export type TrainingMode = "rounds" | "continuous";

/**
 * What a setting whose effect depends on the training mode does in each (issue 39: "PPO
 * steps per round" said "PPO env steps after each round" while continuous training, which
 * trains for as long as a round lasts, does not read it). The form shows the chosen mode's.
 */
export const MODE_HELP: Readonly<Record<string, Readonly<Record<TrainingMode, string>>>> = {
  training: {
    continuous:
      "Continuous: PPO trains while you compare, and each new round shows what the agent does at its end (cut from PPO's latest episodes).",
    rounds: "Rounds: PPO trains after each round ends, for PPO steps per round, while you wait; then the next round is sampled.",
  },
  ppo_steps_per_round: {
    continuous: "Not used in continuous training: PPO trains for as long as a round lasts (pause the round to pause it).",
    rounds: "PPO env steps after each round, on the reward fitted to all answers so far; you wait while they run.",
  },
  final_steps: {
    continuous: "PPO env steps on the learned reward after the last round, before the agent is filmed (empty: 2 × PPO steps per round).",
    rounds: "PPO env steps on the learned reward after the last round, before the agent is filmed (empty: 2 × PPO steps per round).",
  },
  eval_episodes: {
    continuous: "Episodes of the greedy policy per point of the learning chart, measured every few seconds of training beside PPO.",
    rounds: "Episodes of the greedy policy measuring its true return after each round's training.",
  },
};

/** The help `f` shows when the form's training mode is `mode` and its input holds `value`
 * (a choice with help of its own shows the chosen one's: "Teach (measured: …)"). */
export function helpIn(f: SettingField, mode: string, value?: string): string {
  const chosen = value === undefined ? undefined : f.choiceHelp?.[value];
  if (chosen) return chosen;
  const byMode = MODE_HELP[f.key];
  return byMode && (mode === "rounds" || mode === "continuous") ? byMode[mode] : f.help;
}

function refName(schema: JsonSchema): string | null {
  const ref = schema.$ref ?? schema.anyOf?.find((s) => s.$ref)?.$ref;
  return ref ? ref.slice(ref.lastIndexOf("/") + 1) : null;
}

function field(path: string[], schema: JsonSchema, section: string): SettingField {
  const options = schema.anyOf?.filter((s) => s.type !== "null") ?? [];
  const nullable = (schema.anyOf ?? []).some((s) => s.type === "null");
  const core: JsonSchema = { ...(options.length === 1 ? options[0] : {}), ...schema };
  const key = path.join(".");
  const top = path.length === 1 ? path[0]! : "";
  const group: GroupId = GROUPS.feedback.includes(top) ? "feedback" : GROUPS.training.includes(top) ? "training" : "advanced";
  const base = {
    path,
    key,
    label: labelOf(core.title ?? path[path.length - 1]!),
    help: helpOf(core.description),
    nullable,
    group,
    section,
  };
  if (core.enum) {
    const choiceHelp = core["x-choice-help"];
    return { ...base, kind: "choice", choices: core.enum.map(String), ...(choiceHelp ? { choiceHelp } : {}) };
  }
  if (core.type === "boolean") return { ...base, kind: "boolean" };
  if (core.type === "array") {
    const items = core.items ?? core.prefixItems?.[0];
    return { ...base, kind: "list", integerItems: items?.type === "integer" };
  }
  if (core.type === "integer" || core.type === "number") {
    const min = core.minimum ?? core.exclusiveMinimum;
    const max = core.maximum ?? core.exclusiveMaximum;
    const step = core.type === "integer" ? core.multipleOf ?? 1 : "any";
    return {
      ...base,
      kind: core.type,
      step,
      ...(min === undefined ? {} : { min }),
      ...(max === undefined ? {} : { max }),
    };
  }
  return { ...base, kind: "text" };
}

/**
 * Every setting the page offers, in display order: the Feedback and Training groups' named
 * fields, then the other settings, then each nested config's fields (Advanced).
 *
 * Throws when the schema has no `SessionSettings`.
 */
export function settingFields(schemas: Schemas): SettingField[] {
  const settings = schemas[SETTINGS_SCHEMA]?.properties;
  if (!settings) throw new Error(`the server's schema has no ${SETTINGS_SCHEMA}`);
  const plain: SettingField[] = [];
  const nested: SettingField[] = [];
  for (const [name, schema] of Object.entries(settings)) {
    if (HIDDEN.has(name)) continue;
    const ref = refName(schema);
    const inner = ref ? schemas[ref]?.properties : undefined;
    if (inner) {
      const section = SECTION_NAMES[name] ?? labelOf(schemas[ref!]?.title ?? name);
      for (const [sub, subSchema] of Object.entries(inner)) nested.push(field([name, sub], subSchema, section));
    } else plain.push(field([name], schema, "Session"));
  }
  const rank = (f: SettingField): number => {
    const named = [...GROUPS.feedback, ...GROUPS.training].indexOf(f.key);
    return named < 0 ? Number.MAX_SAFE_INTEGER : named;
  };
  return [...plain.sort((a, b) => rank(a) - rank(b)), ...nested];
}

/** The value of `path` in a settings object (undefined when absent). */
export function valueAt(settings: unknown, path: readonly string[]): unknown {
  let value: unknown = settings;
  for (const part of path) value = (value as Record<string, unknown> | null | undefined)?.[part];
  return value;
}

/** What the field's input shows for a value: "" for null, "64, 64" for a list. */
export function inputText(value: unknown): string {
  if (value === null || value === undefined) return "";
  if (Array.isArray(value)) return value.join(", ");
  return String(value);
}

export type Parsed = { ok: true; value: unknown } | { ok: false; error: string };

/** The value an input means, or why it means none. Booleans come as "true" / "false". */
export function parseInput(f: SettingField, raw: string): Parsed {
  const text = raw.trim();
  if (f.kind === "boolean") return { ok: true, value: text === "true" };
  if (f.kind === "choice" || f.kind === "text") return { ok: true, value: raw };
  if (text === "") return f.nullable ? { ok: true, value: null } : { ok: false, error: `${f.label}: enter a value` };
  if (f.kind === "list") {
    const items = text.split(/[\s,]+/).filter(Boolean).map(Number);
    const bad = items.some((n) => !Number.isFinite(n) || (f.integerItems && !Number.isInteger(n)));
    if (bad) return { ok: false, error: `${f.label}: enter ${f.integerItems ? "whole " : ""}numbers separated by commas` };
    return { ok: true, value: items };
  }
  const n = Number(text);
  if (!Number.isFinite(n)) return { ok: false, error: `${f.label}: enter a number` };
  if (f.kind === "integer" && !Number.isInteger(n)) return { ok: false, error: `${f.label}: enter a whole number` };
  return { ok: true, value: n };
}

/** The touched keys after the person edits `key`: editing one of a coupled pair lets the
 * server derive the other again. */
export function touch(touched: ReadonlySet<string>, key: string): Set<string> {
  const next = new Set(touched);
  next.add(key);
  for (const [a, b] of COUPLED) {
    if (key === a) next.delete(b);
    if (key === b) next.delete(a);
  }
  return next;
}

export interface Chosen {
  /** The settings the person chose (the touched fields), nested as the server takes them. */
  settings: Record<string, unknown>;
  /** One sentence per input that means no value. */
  errors: string[];
}

/**
 * The settings to send: the touched fields' values, nested (`ppo.batch_size` →
 * `{ppo: {batch_size}}`). The server fills every other field with the env's default, as
 * the resolved settings the form shows.
 */
export function chosenSettings(
  fields: readonly SettingField[],
  inputs: Readonly<Record<string, string>>,
  touched: ReadonlySet<string>,
): Chosen {
  const settings: Record<string, unknown> = {};
  const errors: string[] = [];
  for (const f of fields) {
    if (!touched.has(f.key)) continue;
    const parsed = parseInput(f, inputs[f.key] ?? "");
    if (!parsed.ok) {
      errors.push(parsed.error);
      continue;
    }
    let into = settings;
    for (const part of f.path.slice(0, -1)) into = (into[part] ??= {}) as Record<string, unknown>;
    into[f.path[f.path.length - 1]!] = parsed.value;
  }
  return { settings, errors };
}

/**
 * A refusal of the server as the form says it: the server names a bad field by its place in
 * the body ("settings.pool_size: Input should be …"); the form names it by the label it shows
 * ("Pool size: Input should be …"), a nested field with its section ("Batch size (PPO): …"), a
 * nested config as its section ("PPO: …"), without pydantic's "Value error, ". Parts the form
 * has no field for stay as they are.
 */
export function refusalText(message: string, fields: readonly SettingField[]): string {
  return message
    .split("; ")
    .map((part) => {
      const m = /^settings\.([\w.]+): ([\s\S]*)$/.exec(part);
      if (!m) return part;
      const [, key, reason] = m as unknown as [string, string, string];
      const f = fields.find((x) => x.key === key);
      const section = fields.find((x) => x.path.length > 1 && x.path[0] === key)?.section;
      const name = f ? (f.path.length > 1 ? `${f.label} (${f.section})` : f.label) : section;
      return name ? `${name}: ${reason.replace(/^Value error, /, "")}` : part;
    })
    .join("; ");
}
