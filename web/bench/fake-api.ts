/**
 * An in-memory stand-in for the server, for the demo page (web/bench.html?demo=groupwise or
 * ?demo=pairwise) and the controller tests: lets the whole UI be looked at and screenshot
 * without a session. Clips are SVG posters (there are no videos).
 *
 * It cannot drift from the server unnoticed: every reply goes through `answer(route, reply)`,
 * whose reply type is the generated one of that route (`api-types.ts`, from `openapi.json`),
 * so a changed schema fails the type check; and test/fake-api.test.ts checks every route in
 * `FAKE_ROUTES` against `openapi.json` itself, replies included.
 */
import openapiDocument from "../openapi.json";
import type { Annotator, Api, EnvInfo, JudgementOut, OpenApiDocument, PairQuery, SessionState } from "../src/api";
import type { paths } from "../src/api-types";
import type { SyntheticRound } from "./synthetic";

type Method = "get" | "post" | "put" | "delete";

/** Every operation of the server's schema, as "method path": "get /api/envs", … */
export type Route = {
  [P in keyof paths]: {
    [M in Method]: paths[P][M] extends { responses: unknown } ? `${M} ${P}` : never;
  }[Method];
}[keyof paths];

type Operation<R extends Route> = R extends `${infer M extends Method} ${infer P extends keyof paths}`
  ? NonNullable<paths[P][M]>
  : never;
type JsonBody<T> = T extends { content: { "application/json": infer B } } ? B : never;

/** The JSON body the server answers `route` with (its 200, else its 201 response; null
 * for a 204). */
export type Reply<R extends Route> =
  Operation<R> extends { responses: infer S }
    ? S extends { 200: infer Ok }
      ? JsonBody<Ok>
      : S extends { 201: infer Created }
        ? JsonBody<Created>
        : S extends { 204: unknown }
          ? null
          : never
    : never;

/** The JSON routes the fake answers; `answer` takes no other. */
export const FAKE_ROUTES = [
  "get /api/envs",
  "get /api/sessions",
  "post /api/sessions",
  "post /api/settings/resolve",
  "get /api/sessions/{session_id}",
  "get /api/sessions/{session_id}/rounds/{round_index}/tree",
  "get /api/sessions/{session_id}/rounds/{round_index}/edges",
  "get /api/sessions/{session_id}/judgements",
  "post /api/sessions/{session_id}/rounds/{round_index}/next-suggestion",
  "get /api/sessions/{session_id}/pairwise/next",
  "post /api/sessions/{session_id}/pairwise/skip",
  "post /api/sessions/{session_id}/judgements",
  "delete /api/sessions/{session_id}/judgements/{judgement_id}",
  "post /api/sessions/{session_id}/rounds/{round_index}/shown",
  "post /api/sessions/{session_id}/pause",
  "post /api/sessions/{session_id}/resume",
  "post /api/sessions/{session_id}/end-round",
  "post /api/sessions/{session_id}/retry",
  "post /api/sessions/{session_id}/finish",
  "post /api/sessions/{session_id}/continue",
  "get /api/sessions/{session_id}/agent",
  "put /api/sessions/{session_id}/agent/round",
  "get /api/sessions/{session_id}/training",
  "get /api/sessions/{session_id}/annotators",
  "post /api/sessions/{session_id}/annotators",
  "delete /api/sessions/{session_id}/annotators/{annotator_id}",
] as const satisfies readonly Route[];
export type FakeRoute = (typeof FAKE_ROUTES)[number];

/** The routes the fake's URLs and event stream stand in for (files, video, SSE). */
export const FAKE_URL_ROUTES = {
  clipUrl: "get /clips/{clip_id}",
  exportUrl: "get /api/sessions/{session_id}/export",
  agentVideoUrl: "get /api/sessions/{session_id}/agent.mp4",
  agentZipUrl: "get /api/sessions/{session_id}/agent.zip",
  agentRoundVideoUrl: "get /api/sessions/{session_id}/agent/rounds/{round_index}.mp4",
  events: "get /api/sessions/{session_id}/events",
} as const satisfies Partial<Record<keyof Api, Route>>;

/** One reply of the fake, as the drift test reads it. */
export interface Served {
  route: FakeRoute;
  reply: unknown;
}

const HUES = [28, 200, 140, 280, 350, 60, 170, 230];

function poster(id: string): string {
  const i = Number(id.replace(/\D/g, "")) || 0;
  const hue = HUES[i % HUES.length]!;
  const x = 20 + ((i * 37) % 60);
  const y = 20 + ((i * 53) % 60);
  const svg =
    `<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">` +
    `<rect width="100" height="100" fill="hsl(${hue},25%,88%)"/>` +
    `<g stroke="hsl(${hue},15%,75%)" stroke-width="0.6">` +
    [20, 40, 60, 80].map((v) => `<line x1="${v}" y1="0" x2="${v}" y2="100"/><line x1="0" y1="${v}" x2="100" y2="${v}"/>`).join("") +
    `</g><circle cx="${x}" cy="${y}" r="7" fill="hsl(${hue},60%,40%)"/>` +
    `<rect x="${100 - x}" y="${100 - y}" width="12" height="12" fill="hsl(${(hue + 180) % 360},55%,45%)"/></svg>`;
  return `data:image/svg+xml,${encodeURIComponent(svg)}`;
}

const pq = (a: string, b: string): PairQuery => ({
  left: a,
  right: b,
  left_clip: `${a}.mp4`,
  right_clip: `${b}.mp4`,
  left_poster: `${a}.jpg`,
  right_poster: `${b}.jpg`,
});

const ENVS: EnvInfo[] = ["GridWorld", "Hopper", "HalfCheetah"].map((name) => ({
  name,
  gym_id: `groupwise/${name}-v0`,
  kind: "env",
  horizon: 1000,
  clip_seconds: 1,
  description: "",
  target: null,
}));

export function fakeApi(
  round: SyntheticRound,
  mode: "groupwise" | "pairwise",
  state: Partial<SessionState> = {},
  /** Hears every reply (test/fake-api.test.ts checks them against the schema). */
  onServe?: (served: Served) => void,
): Api {
  let judgements = round.judgements.slice();
  let nextId = Math.max(0, ...judgements.map((j) => j.id)) + 1;
  let used = 0;
  const person = (id: string, name: string, comparisons: number): Annotator => ({
    id,
    name,
    comparisons,
    pairs: 4 * comparisons,
    shown_s: 11 * comparisons,
    agreement: { kappa: comparisons ? 0.41 : null, share: comparisons ? 0.72 : null, n: 3 * comparisons },
    model_agreement: { share: comparisons ? 0.8 : null, n: 4 * comparisons },
  });
  let people: Annotator[] = [person("owner", "owner", 14)];
  let nextPerson = 1;
  const session: SessionState = {
    id: "s-demo",
    env: "GridWorld",
    mode,
    annotator: "",
    settings: {
      pool_size: round.leaves.length,
      pool_variants: 0,
      ppo_preset: "study",
      pretrain_steps: 0,
      fragment_length: 30,
      round_seconds: 600,
      comparisons_per_round: 20,
      ppo_steps_per_round: 20000,
      rounds: 5,
      suggestions: round.suggestions.length,
      seed: 0,
      eval_episodes: 5,
      exploration_fraction: 0.25,
      frame_size: 240,
      render_workers: 1,
      driver: "app",
      pair_derivation: "cover",
      pair_oversample: 1,
      training: "rounds",
      recipe: "paper",
      lease_s: 60,
      overlap_share: 0.1,
    },
    round: 1,
    rounds: 5,
    phase: "ready",
    progress: { phase: "", fraction: 0, message: "" },
    error: null,
    timer: { elapsed_s: 95, budget_s: 600, paused: false, running: true, shown_at: null },
    counts: { comparisons_round: judgements.length, pairs_round: 0, comparisons_total: 24, pairs_total: 103 },
    created_at: new Date().toISOString(),
    me: { id: "owner", name: "owner", owner: true },
    annotators: people,
    ...state,
  };
  /** Who answers on this fake page. */
  const me = () => ({ id: session.me.id, name: session.me.name });

  function answer<R extends FakeRoute>(route: R, reply: Reply<R>): Reply<R> {
    onServe?.({ route, reply });
    return reply;
  }

  /** The round the person picked as the take-away agent; null: the last (the default). */
  let picked: number | null = null;
  const agentOut = (): Reply<"get /api/sessions/{session_id}/agent"> => ({
    env: session.env,
    round: picked ?? session.round,
    chosen_by: picked === null ? "last" : "person",
    env_steps: 140_000,
    measure: "true return",
    true_return_mean: 41.5,
    true_return_std: 3.2,
    target: null,
    target_score_mean: null,
    target_score_std: null,
    video: {
      seconds: 3.3,
      fps: 30,
      frames: 100,
      width: 240,
      height: 240,
      episode_return: 43,
      target_score: null,
    },
    rounds: [12, 18, 25, 31, 36, 41.5].map((value, i) => ({
      round: i,
      feedback: i < 5,
      checkpoint: true,
      video: false,
      judgements: i < 5 ? 6 : 0,
      pairs_total: 20 * Math.min(i + 1, 5),
      env_steps: 20_000 * (i + 1),
      true_return_mean: value,
      true_return_std: 3,
      target_score_mean: null,
      target_score_std: null,
    })),
  });

  const api: Api = {
    invalidate: () => undefined,
    envs: async () => answer("get /api/envs", ENVS),
    sessions: async () => answer("get /api/sessions", [{ ...session }]),
    createSession: async () => answer("post /api/sessions", { ...session }),
    // Not a route of the schema: FastAPI serves the schema itself beside it. JSON imports
    // are typed loosely; the drift test checks this is the document.
    openapi: async () => openapiDocument as unknown as OpenApiDocument,
    resolveSettings: async () => answer("post /api/settings/resolve", { ...session.settings }),
    session: async () => answer("get /api/sessions/{session_id}", { ...session }),
    tree: async () =>
      answer("get /api/sessions/{session_id}/rounds/{round_index}/tree", {
        round: 1,
        levels: round.levels,
        tree: round.tree,
        medoids: round.medoids,
        compared: [],
      }),
    edges: async (_s, _r, k) =>
      answer("get /api/sessions/{session_id}/rounds/{round_index}/edges", round.suggestions.slice(0, k)),
    judgements: async () =>
      answer("get /api/sessions/{session_id}/judgements", judgements.map((j) => ({ ...j, round: 1 }))),
    nextSuggestion: async () => {
      const a = round.candidates[(used * 2) % round.candidates.length]!;
      const b = round.candidates[(used * 2 + 1) % round.candidates.length]!;
      used++;
      return answer("post /api/sessions/{session_id}/rounds/{round_index}/next-suggestion", {
        suggestion: { id: used, left: a.leaves, right: b.leaves, left_node: a.id, right_node: b.id, score: 0.8 },
      });
    },
    pairwiseNext: async () =>
      answer("get /api/sessions/{session_id}/pairwise/next", { pair: pq("b4", "b90"), following: pq("b17", "b33") }),
    skipPair: async () =>
      answer("post /api/sessions/{session_id}/pairwise/skip", { pair: pq("b17", "b33"), following: pq("b5", "b61") }),
    submitJudgement: async (_sid, body) => {
      const n = Math.max(body.left.length, body.right.length);
      const value = body.label === "left" ? 1 : body.label === "right" ? 0 : 0.5;
      const j: JudgementOut = {
        ...body,
        annotator: me(),
        suggestion_id: null,
        id: nextId++,
        created_at: new Date().toISOString(),
        undone: false,
        pairs: Array.from({ length: n }, (_, i) => ({
          a: body.left[i % body.left.length]!,
          b: body.right[i % body.right.length]!,
          label: value,
        })),
      };
      judgements = [...judgements, j];
      return answer("post /api/sessions/{session_id}/judgements", j);
    },
    undoJudgement: async (_sid, id) => {
      const j = judgements.find((x) => x.id === id)!;
      judgements = judgements.filter((x) => x.id !== id);
      return answer("delete /api/sessions/{session_id}/judgements/{judgement_id}", { ...j, undone: true });
    },
    shown: async () => {
      session.timer.shown_at ??= new Date().toISOString();
      session.timer.running = !session.timer.paused;
      return answer("post /api/sessions/{session_id}/rounds/{round_index}/shown", { ...session });
    },
    control: async (_sid, action) => {
      if (action === "pause") session.timer.paused = true;
      if (action === "resume") session.timer.paused = false;
      session.timer.running = !session.timer.paused;
      if (action === "end-round") {
        session.phase = "training";
        session.progress = { phase: "ppo", fraction: 0.42, message: "PPO 8,400 / 20,000 steps" };
      }
      return answer(`post /api/sessions/{session_id}/${action}`, { ...session });
    },
    finish: async () => {
      session.phase = "training";
      session.rounds = session.round + 1;
      return answer("post /api/sessions/{session_id}/finish", { ...session });
    },
    continueTraining: async () => {
      session.phase = "finishing";
      session.round += 1;
      return answer("post /api/sessions/{session_id}/continue", { ...session });
    },
    agent: async () => answer("get /api/sessions/{session_id}/agent", agentOut()),
    pickAgent: async (_sid, r) => {
      picked = r;
      return answer("put /api/sessions/{session_id}/agent/round", agentOut());
    },
    annotators: async () =>
      answer("get /api/sessions/{session_id}/annotators", people.map((p) => ({ ...p }))),
    addAnnotator: async (_sid, name) => {
      const id = `a-${nextPerson++}`;
      people = [...people, person(id, name.trim(), 0)];
      session.annotators = people;
      const token = `token-${id}`;
      return answer("post /api/sessions/{session_id}/annotators", {
        id,
        name: name.trim(),
        token,
        link: `?session=${session.id}&token=${token}`,
      });
    },
    removeAnnotator: async (_sid, aid) => {
      people = people.filter((p) => p.id !== aid);
      session.annotators = people;
      return answer("delete /api/sessions/{session_id}/annotators/{annotator_id}", null);
    },
    clipUrl: (clip) => (clip.endsWith(".jpg") || clip.endsWith(".mp4") ? poster(clip) : clip),
    exportUrl: () => "#",
    agentVideoUrl: () => "",
    agentZipUrl: () => "#",
    agentRoundVideoUrl: () => "",
    training: async () => {
      const start = Date.parse(session.created_at);
      const points = [-40, -31, -22, -18, -9, -4].map((value, i) => ({
        round: session.round,
        at: new Date(start + 20_000 * i).toISOString(),
        ppo_steps: 2048 * 3 * i,
        true_return: value,
        pairs: 20 + 9 * i,
        reward_val_accuracy: 0.7 + 0.02 * i,
        pool_steps: 0,
      }));
      const last = points[points.length - 1]!;
      return answer("get /api/sessions/{session_id}/training", {
        points,
        summary: {
          round: last.round,
          ppo_steps: last.ppo_steps,
          pairs: last.pairs,
          reward_val_accuracy: last.reward_val_accuracy,
          pool_age: last.ppo_steps - last.pool_steps,
          true_return: last.true_return,
        },
      });
    },
    events: (_sid, handlers) => {
      setTimeout(() => handlers.open?.(), 0);
      return () => undefined;
    },
  };
  return api;
}
