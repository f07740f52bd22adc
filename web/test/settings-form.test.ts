import { describe, expect, it } from "vitest";
import openapi from "../openapi.json";
import {
  GROUPS,
  MODE_HELP,
  type Schemas,
  type SettingField,
  chosenSettings,
  helpIn,
  helpOf,
  inputText,
  labelOf,
  parseInput,
  refusalText,
  settingFields,
  touch,
  valueAt,
} from "../src/lib/settings-form";

const schemas = (openapi as unknown as { components: { schemas: Schemas } }).components.schemas;
const fields = settingFields(schemas);
const byKey = new Map(fields.map((f) => [f.key, f]));
const field = (key: string) => byKey.get(key)!;

/** The server's schema with a nested config, as the settings once held PPO's whole config:
 * the form offers any nested config's fields, in a section of Advanced. */
const nestedSchemas = structuredClone(schemas);
nestedSchemas.SessionSettings!.properties!.ppo = { $ref: "#/components/schemas/PPOConfig" };
nestedSchemas.PPOConfig = {
  title: "PPOConfig",
  properties: {
    learning_rate: { type: "number", title: "Learning Rate", exclusiveMinimum: 0 },
    batch_size: { type: "integer", title: "Batch Size", minimum: 2 },
    gae_lambda: { type: "number", title: "Gae Lambda" },
    net_arch: { type: "array", title: "Net Arch", items: { type: "integer" } },
    l2_range: { type: "array", title: "L2 Range", prefixItems: [{ type: "number" }, { type: "number" }] },
    normalize_obs: { type: "boolean", title: "Normalize Obs" },
  },
};
const nested = settingFields(nestedSchemas);
const nestedField = (key: string) => nested.find((f) => f.key === key)!;

describe("settingFields", () => {
  it("offers every SessionSettings field but the driver and research, each with a one-line help", () => {
    const top = Object.keys(schemas.SessionSettings!.properties!).filter((k) => !["driver", "research"].includes(k));
    for (const key of top) expect(byKey.has(key), key).toBe(true);
    expect(fields.map((f) => f.key).sort()).toEqual([...top].sort());
    for (const f of fields) {
      expect(f.help.length, f.key).toBeGreaterThan(0);
      expect(f.help.length, f.key).toBeLessThanOrEqual(120);
      expect(f.help, f.key).not.toMatch(/SPEC|issue \d/);
    }
  });

  it("groups them: Feedback and Training in the page's order, the rest Advanced", () => {
    const keys = (group: string) => fields.filter((f) => f.group === group).map((f) => f.key);
    expect(keys("feedback")).toEqual([
      "comparisons_per_round",
      "rounds",
      "round_seconds",
      "pool_size",
      "clip_seconds",
      "fragment_length",
      "pair_derivation",
    ]);
    expect(keys("training")).toEqual([
      "training",
      "ppo_steps_per_round",
      "final_steps",
      "recipe",
      "ppo_preset",
      "pretrain_steps",
      "pool_variants",
      "reward_inputs",
      "exploration_fraction",
      "teach_log_std",
      "seed",
      "eval_episodes",
    ]);
    expect(new Set(fields.filter((f) => f.group === "advanced").map((f) => f.section))).toEqual(new Set(["Session"]));
    expect(field("frame_size").section).toBe("Session");
  });

  it("puts a nested config's fields in its own section of Advanced", () => {
    expect(nestedField("ppo.gae_lambda")).toMatchObject({ group: "advanced", section: "PPO", label: "GAE lambda" });
    expect(nested.slice(-6).map((f) => f.key)).toEqual([
      "ppo.learning_rate",
      "ppo.batch_size",
      "ppo.gae_lambda",
      "ppo.net_arch",
      "ppo.l2_range",
      "ppo.normalize_obs",
    ]);
  });

  it("puts a setting the server adds in Advanced, without page changes", () => {
    const more = structuredClone(schemas);
    more.SessionSettings!.properties!.colour_blind = { type: "boolean", title: "Colour Blind" };
    const f = settingFields(more).find((x) => x.key === "colour_blind")!;
    expect([f.group, f.section, f.kind, f.label]).toEqual(["advanced", "Session", "boolean", "Colour blind"]);
  });

  it("takes the bounds, kinds and nullability from the schema", () => {
    expect(field("pool_size")).toMatchObject({ kind: "integer", min: 8, max: 1000, step: 1, nullable: false });
    expect(field("clip_seconds")).toMatchObject({ kind: "number", min: 0, max: 20, step: "any", nullable: true });
    expect(field("final_steps")).toMatchObject({ kind: "integer", min: 0, max: 10_000_000, nullable: true });
    expect(field("frame_size").step).toBe(2);
    expect(field("pair_derivation")).toMatchObject({ kind: "choice", choices: ["cover", "cartesian"] });
    expect(field("ppo_preset")).toMatchObject({ kind: "choice", choices: ["study", "mujoco", "mujoco-entropy"], nullable: true });
    expect(field("pool_variants")).toMatchObject({ kind: "integer", min: 0, max: 32, nullable: true });
    expect(field("reward_inputs")).toMatchObject({ kind: "choice", choices: ["obs", "obs-act"], nullable: true });
    expect(field("recipe")).toMatchObject({ kind: "choice", choices: ["teach", "paper"] });
    expect(nestedField("ppo.net_arch")).toMatchObject({ kind: "list", integerItems: true });
    expect(nestedField("ppo.l2_range")).toMatchObject({ kind: "list", integerItems: false });
    expect(nestedField("ppo.normalize_obs").kind).toBe("boolean");
  });

  it("labels from the titles, help from the descriptions", () => {
    expect(field("ppo_steps_per_round").label).toBe("PPO steps per round");
    expect(field("clip_seconds").label).toBe("Clip seconds");
    expect(field("pretrain_steps").label).toBe("Pretrain steps");
    expect(field("pool_size").help).toBe("behaviours per round");
    expect(field("final_steps").help).toContain("(empty: 2 × ppo steps per round");
  });

  it("says so when the schema has no settings", () => {
    expect(() => settingFields({})).toThrow("SessionSettings");
  });
});

describe("values", () => {
  it("shows a stored value in its input", () => {
    const settings = { clip_seconds: null, ppo: { net_arch: [32, 32] }, pool_size: 100 };
    expect(inputText(valueAt(settings, ["ppo", "net_arch"]))).toBe("32, 32");
    expect(inputText(valueAt(settings, ["clip_seconds"]))).toBe("");
    expect(inputText(valueAt(settings, ["pool_size"]))).toBe("100");
    expect(valueAt(settings, ["reward", "lr"])).toBeUndefined();
  });

  it("parses what a person types, or says why not", () => {
    expect(parseInput(field("pool_size"), " 40 ")).toEqual({ ok: true, value: 40 });
    expect(parseInput(field("pool_size"), "4.5")).toEqual({ ok: false, error: "Pool size: enter a whole number" });
    expect(parseInput(field("pool_size"), "")).toEqual({ ok: false, error: "Pool size: enter a value" });
    expect(parseInput(field("clip_seconds"), "")).toEqual({ ok: true, value: null });
    expect(parseInput(field("clip_seconds"), "2.5")).toEqual({ ok: true, value: 2.5 });
    expect(parseInput(field("clip_seconds"), "abc").ok).toBe(false);
    expect(parseInput(nestedField("ppo.net_arch"), "16, 16 8")).toEqual({ ok: true, value: [16, 16, 8] });
    expect(parseInput(nestedField("ppo.net_arch"), "16, 1.5").ok).toBe(false);
    expect(parseInput(nestedField("ppo.normalize_obs"), "false")).toEqual({ ok: true, value: false });
    expect(parseInput(field("pair_derivation"), "cartesian")).toEqual({ ok: true, value: "cartesian" });
  });
});

describe("chosenSettings", () => {
  it("sends only the touched fields, nested as the server takes them", () => {
    const inputs = { clip_seconds: "2", pool_size: "100", "ppo.learning_rate": "0.0005", "ppo.net_arch": "16" };
    const touched = new Set(["clip_seconds", "ppo.learning_rate", "ppo.net_arch"]);
    expect(chosenSettings(nested, inputs, touched)).toEqual({
      settings: { clip_seconds: 2, ppo: { learning_rate: 0.0005, net_arch: [16] } },
      errors: [],
    });
  });

  it("leaves out what means no value, and says why", () => {
    const chosen = chosenSettings(fields, { rounds: "two" }, new Set(["rounds"]));
    expect(chosen).toEqual({ settings: {}, errors: ["Rounds: enter a number"] });
  });

  it("lets the server derive one of a coupled pair from the other", () => {
    let touched = touch(new Set(), "fragment_length");
    touched = touch(touched, "clip_seconds");
    expect([...touched]).toEqual(["clip_seconds"]);
    expect([...touch(touched, "fragment_length")]).toEqual(["fragment_length"]);
    expect([...touch(new Set(["seed"]), "rounds")].sort()).toEqual(["rounds", "seed"]);
  });
});

describe("refusalText", () => {
  it("names a refused field by the label the form shows, not its place in the body", () => {
    expect(refusalText("settings.pool_size: Input should be less than or equal to 1000", fields)).toBe(
      "Pool size: Input should be less than or equal to 1000",
    );
    expect(refusalText("settings.ppo.batch_size: Input should be greater than or equal to 2", nested)).toBe(
      "Batch size (PPO): Input should be greater than or equal to 2",
    );
    expect(
      refusalText(
        "settings.pool_size: Input should be a valid integer; settings.ppo_steps_per_round: Input should be greater than or equal to 0",
        fields,
      ),
    ).toBe("Pool size: Input should be a valid integer; PPO steps per round: Input should be greater than or equal to 0");
  });

  it("names a nested config by its section and leaves other sentences alone", () => {
    expect(refusalText("settings.ppo: Value error, ppo batch_size 4096 is larger than a rollout", nested)).toBe(
      "PPO: ppo batch_size 4096 is larger than a rollout",
    );
    const plain = "fragment_length 7 and clip_seconds 1.0 (30 steps of GridWorld) disagree: give one of them";
    expect(refusalText(plain, fields)).toBe(plain);
    expect(refusalText("settings.driver: Input should be 'app' or 'library'", fields)).toBe(
      "settings.driver: Input should be 'app' or 'library'",
    );
  });
});

describe("labelOf and helpOf", () => {
  it("speaks plainly", () => {
    expect(labelOf("N Envs")).toBe("N envs");
    expect(labelOf("initial_l2")).toBe("Initial L2");
    expect(helpOf("L, steps per behaviour (null: clip_seconds of simulated time)")).toBe(
      "L, steps per behaviour (empty: clip seconds of simulated time)",
    );
    expect(helpOf(undefined)).toBe("");
    expect(helpOf("Passes over the dataset per fit.\nOn a simulated session 3 beat 1.")).toBe(
      "Passes over the dataset per fit.",
    );
  });
});

describe("the Training section says what each setting does in the chosen mode (issue 39)", () => {
  it("holds the training mode, with help that is not cut at a colon", () => {
    expect(GROUPS.training[0]).toBe("training");
    expect(helpOf("continuous: the agent trains while you compare; rounds: it trains after each round ends")).toBe(
      "continuous: the agent trains while you compare; rounds: it trains after each round ends",
    );
  });

  it("tells what PPO steps per round do in each mode", () => {
    const f = { key: "ppo_steps_per_round", help: "PPO env steps after each round" } as SettingField;
    expect(helpIn(f, "continuous")).toMatch(/^Not used in continuous training/);
    expect(helpIn(f, "rounds")).toMatch(/^PPO env steps after each round/);
    const other = { key: "seed", help: "the random seed" } as SettingField;
    expect(helpIn(other, "continuous")).toBe("the random seed");
    for (const [key, byMode] of Object.entries(MODE_HELP)) {
      for (const words of Object.values(byMode)) expect(words.length, key).toBeLessThan(160);
    }
  });
});

describe("the recipe shows its measured success in one line (issue 39)", () => {
  it("tells the chosen recipe's success, from the server's schema", () => {
    const f = field("recipe");
    expect(helpIn(f, "continuous", "teach")).toBe(
      "Teach (measured: stand-up 5/5, backflip 5/5 seeds at 10 and at 20 minutes of a simulated person; the splits unmet; docs/results/continuous)",
    );
    expect(helpIn(f, "rounds", "paper")).toMatch(/^Paper \(measured: /);
    expect(helpIn(f, "rounds", "")).toBe(f.help); // nothing chosen yet: the field's own help
    expect(helpIn(field("seed"), "rounds", "3")).toBe(field("seed").help);
  });
});
