/**
 * The fake server (bench/fake-api.ts) against the server's schema, `openapi.json`: every
 * route it answers or stands in for is an operation there, and every reply it gives carries
 * what the server's response model for that route carries, all the way down. Its types come
 * from the same schema (api-types.ts); this also catches an openapi.json regenerated without
 * `npm run types`, and a fake member that answers without saying which route.
 */
import { describe, expect, it } from "vitest";
import openapi from "../openapi.json";
import type { Api } from "../src/api";
import { FAKE_ROUTES, FAKE_URL_ROUTES, type FakeRoute, type Served, fakeApi } from "../bench/fake-api";
import { syntheticRound } from "../bench/synthetic";

/** The part of JSON Schema (as FastAPI writes it) the check reads. */
interface Schema {
  $ref?: string;
  type?: string | string[];
  enum?: unknown[];
  const?: unknown;
  default?: unknown;
  anyOf?: Schema[];
  oneOf?: Schema[];
  allOf?: Schema[];
  items?: Schema;
  properties?: Record<string, Schema>;
  required?: string[];
  additionalProperties?: Schema | boolean;
}

interface Operation {
  responses: Record<string, { content?: Record<string, { schema?: Schema }> }>;
}

const doc = openapi as unknown as {
  paths: Record<string, Record<string, Operation>>;
  components: { schemas: Record<string, Schema> };
};

function operation(route: string): Operation | undefined {
  const [method, path] = route.split(" ") as [string, string];
  return doc.paths[path]?.[method];
}

/** The JSON schema of the route's 200 (else 201) response; a 204's body is nothing (null). */
function replySchema(route: string): Schema | undefined {
  const responses = operation(route)?.responses ?? {};
  if (responses["204"] && !responses["200"] && !responses["201"]) return { type: "null" };
  return (responses["200"] ?? responses["201"])?.content?.["application/json"]?.schema;
}

function resolve(schema: Schema): Schema {
  if (!schema.$ref) return schema;
  const name = schema.$ref.replace("#/components/schemas/", "");
  const target = doc.components.schemas[name];
  if (!target) throw new Error(`openapi.json has no schema ${name}`);
  return resolve(target);
}

/**
 * The properties every reply carries: the `required` ones, and those with a non-null
 * default (the server serialises every field, and openapi-typescript types these as always
 * present, so the page may read them without a check).
 */
function carried(schema: Schema): string[] {
  const withDefault = Object.entries(schema.properties ?? {})
    .filter(([, p]) => p.default !== undefined && p.default !== null)
    .map(([name]) => name);
  return [...new Set([...(schema.required ?? []), ...withDefault])];
}

const TYPE_CHECKS: Record<string, (v: unknown) => boolean> = {
  null: (v) => v === null,
  boolean: (v) => typeof v === "boolean",
  integer: (v) => Number.isInteger(v),
  number: (v) => typeof v === "number",
  string: (v) => typeof v === "string",
  array: (v) => Array.isArray(v),
  object: (v) => typeof v === "object" && v !== null && !Array.isArray(v),
};

/** Where `value` departs from `schema`, one "where: what" line each (none: it conforms). */
function problems(value: unknown, raw: Schema, where = "reply"): string[] {
  const schema = resolve(raw);
  const alternatives = schema.anyOf ?? schema.oneOf;
  if (alternatives) {
    const each = alternatives.map((alt) => problems(value, alt, where));
    if (each.some((p) => p.length === 0)) return [];
    // Report against an alternative of the value's own type (the model, not the null).
    const ofItsType = each.filter((p) => !p.some((line) => line.startsWith(`${where}: `)));
    const pool = ofItsType.length ? ofItsType : each;
    return pool.reduce((best, p) => (p.length < best.length ? p : best));
  }
  const found = (schema.allOf ?? []).flatMap((part) => problems(value, part, where));
  if (schema.enum && !schema.enum.includes(value)) found.push(`${where}: ${JSON.stringify(value)} is not one of ${JSON.stringify(schema.enum)}`);
  if ("const" in schema && value !== schema.const) found.push(`${where}: ${JSON.stringify(value)} is not ${JSON.stringify(schema.const)}`);
  const types = schema.type === undefined ? (schema.properties ? ["object"] : []) : [schema.type].flat();
  if (types.length && !types.some((t) => TYPE_CHECKS[t]?.(value))) {
    return [...found, `${where}: ${JSON.stringify(value)?.slice(0, 40)} is not ${types.join(" or ")}`];
  }
  if (Array.isArray(value) && schema.items) {
    value.forEach((item, i) => found.push(...problems(item, schema.items!, `${where}[${i}]`)));
  }
  if (TYPE_CHECKS.object!(value) && (schema.properties || schema.additionalProperties !== undefined)) {
    const object = value as Record<string, unknown>;
    for (const name of carried(schema)) {
      if (!(name in object)) found.push(`${where}.${name}: missing`);
    }
    for (const [name, v] of Object.entries(object)) {
      const declared = schema.properties?.[name];
      const extra = schema.additionalProperties;
      if (declared) found.push(...problems(v, declared, `${where}.${name}`));
      else if (typeof extra === "object") found.push(...problems(v, extra, `${where}.${name}`));
      else if (extra !== true) found.push(`${where}.${name}: not in the schema`);
    }
  }
  return found;
}

const round = syntheticRound(40, { suggestions: 20, history: 30, seed: 5 });

/** Calls every member of a fresh fake once or more; what each answered, by member. */
async function exercise(mode: "groupwise" | "pairwise") {
  const served: Served[] = [];
  const api = fakeApi(round, mode, {}, (s) => served.push(s));
  const answered = new Map<keyof Api, FakeRoute[]>();
  async function call<K extends keyof Api>(member: K, ...args: Parameters<Api[K]>) {
    const before = served.length;
    const fn = api[member] as (...a: Parameters<Api[K]>) => ReturnType<Api[K]>;
    const result = await fn(...args);
    answered.set(member, [...(answered.get(member) ?? []), ...served.slice(before).map((s) => s.route)]);
    return result;
  }
  const sid = "s-demo";
  await call("invalidate", "session");
  await call("envs");
  await call("sessions");
  await call("createSession", { env: "GridWorld", mode });
  await call("openapi");
  await call("resolveSettings", { env: "GridWorld", mode, settings: { rounds: 3 } });
  await call("session", sid);
  await call("tree", sid, 1);
  await call("edges", sid, 1, 5);
  await call("judgements", sid, 1);
  await call("nextSuggestion", sid, 1);
  await call("pairwiseNext", sid);
  await call("skipPair", sid, { left: "b4", right: "b90" });
  const j = await call("submitJudgement", sid, {
    client_id: "c-drift",
    round: 1,
    left: ["b1", "b2"],
    right: ["b3"],
    label: "left",
    source: "explored",
    seconds: 2,
    edits: 1,
    annotator: "",
  });
  await call("undoJudgement", sid, j.id);
  await call("annotators", sid);
  const added = await call("addAnnotator", sid, "Ann");
  await call("removeAnnotator", sid, added.id);
  await call("shown", sid, 1);
  for (const action of ["pause", "resume", "end-round", "retry"] as const) await call("control", sid, action);
  await call("finish", sid);
  await call("continueTraining", sid, { steps: 1000 });
  await call("agent", sid);
  await call("pickAgent", sid, 0);
  await call("training", sid);
  await call("clipUrl", "b1.mp4");
  await call("exportUrl", sid);
  await call("agentVideoUrl", sid, 1);
  await call("agentZipUrl", sid, 1);
  await call("agentRoundVideoUrl", sid, 0);
  const close = await call("events", sid, {});
  close();
  return { api, served, answered };
}

const runs = await Promise.all([exercise("groupwise"), exercise("pairwise")]);
const served = runs.flatMap((r) => r.served);

describe("the fake server against openapi.json", () => {
  it.each([...FAKE_ROUTES, ...Object.values(FAKE_URL_ROUTES)])("%s is an operation of the schema", (route) => {
    expect(operation(route), `${route} is not in openapi.json`).toBeDefined();
  });

  it("answers every route it lists in the exercise, so every reply below is checked", () => {
    expect(new Set(served.map((s) => s.route))).toEqual(new Set(FAKE_ROUTES));
  });

  it("names the route of every member that answers (the rest stand in for URLs or the schema)", () => {
    const { api, answered } = runs[0]!;
    expect([...answered.keys()].sort()).toEqual(Object.keys(api).sort()); // the exercise calls every member
    const silent = [...answered].filter(([, routes]) => routes.length === 0).map(([member]) => member);
    expect(silent.sort()).toEqual(["invalidate", "openapi", ...Object.keys(FAKE_URL_ROUTES)].sort());
  });

  it.each(FAKE_ROUTES)("every reply of %s carries what the schema's response model carries", (route) => {
    const schema = replySchema(route);
    expect(schema, `${route} has no JSON response in openapi.json`).toBeDefined();
    const replies = served.filter((s) => s.route === route);
    expect(replies.flatMap((s) => problems(s.reply, schema!))).toEqual([]);
  });

  it("answers the schema route with the schema itself", async () => {
    expect(await runs[0]!.api.openapi()).toEqual(openapi);
  });
});

describe("the schema check", () => {
  const judgement = served.find((s) => s.route === "post /api/sessions/{session_id}/judgements")!.reply as Record<string, unknown>;
  const judgementSchema: Schema = { $ref: "#/components/schemas/JudgementOut" };

  it("passes a reply as the server sends it", () => {
    expect(problems(judgement, judgementSchema)).toEqual([]);
  });

  it("names a missing property, a wrong type and a property the server does not send", () => {
    const { created_at: _, ...rest } = judgement;
    expect(problems({ ...rest, edits: "1", colour: "red" }, judgementSchema)).toEqual([
      "reply.created_at: missing",
      'reply.edits: "1" is not integer',
      "reply.colour: not in the schema",
    ]);
  });

  it("looks inside arrays, nested models and nullable fields", () => {
    const tree = served.find((s) => s.route.endsWith("/tree"))!.reply as { tree: { children: object[] } };
    const broken = { ...tree, clip: { fps: 30 }, tree: { ...tree.tree, children: [{ id: "b1", level: 0 }] } };
    const found = problems(broken, { $ref: "#/components/schemas/RoundTree" });
    expect(found).toContain("reply.tree.children[0].kind: missing");
    expect(found).toContain("reply.clip.steps: missing");
  });

  it("counts a field with a non-null default as always sent (SessionSettings has no `required`)", () => {
    expect(problems({ pool_size: 40 }, { $ref: "#/components/schemas/SessionSettings" })).toContain(
      "reply.comparisons_per_round: missing",
    );
  });
});
