/**
 * The only module that talks to the server (docs/app.md): fetch for the JSON endpoints,
 * EventSource for `/events`, URLs for `/clips`.
 *
 * - Reads of a resource (session, tree, edges, judgements, suggestion, pairwise) resolve to
 *   `STALE` when a newer read of the same resource was issued, or the resource was
 *   invalidated (an SSE `state` event, a control reply), before the response arrived; the
 *   caller drops them.
 * - Every failure is an `ApiError` whose message is one sentence for the person: the
 *   server's `detail`, FastAPI's validation list flattened, or a sentence for a network
 *   failure.
 * - A judgement is retried with the same `client_id` on network failures and 502–504, so the
 *   server stores it once (it answers a retry with 200 and the same body).
 */
import type { components } from "./api-types";
import { Latest } from "./lib/latest";
import type { JsonSchema } from "./lib/settings-form";

type Schemas = components["schemas"];
/** Who made a judgement (shared sessions, docs/teams.md): "owner" or an annotator's id. */
export type AnnotatorRef = Schemas["AnnotatorRef"];
/** A person of the session with their counters and agreement (`GET …/annotators`). */
export type Annotator = Schemas["AnnotatorOut"];
/** The annotator added: `link` opens the session with their own `token` (shown once). */
export type AnnotatorCreated = Schemas["AnnotatorCreated"];
/** Who this page is in the session. */
export type Me = Schemas["MeOut"];
export type SessionState = Schemas["SessionState"];
export type Settings = Schemas["SessionSettings"];
/** Settings left out take the server's defaults. */
export type SessionCreate = Omit<Schemas["SessionCreate"], "settings" | "annotator"> & {
  settings?: Partial<Settings>;
  annotator?: string;
};
export type RoundTree = Schemas["RoundTree"];
export type ClipTiming = Schemas["ClipTiming"];
export type TreeNodeJson = Schemas["TreeNodeOut"];
export type Edge = Schemas["Edge"];
export type Suggestion = Schemas["Suggestion"];
export type JudgementIn = Schemas["JudgementIn"];
export type JudgementOut = Schemas["JudgementOut"];
export type Pair = Schemas["PairOut"];
export type PairQuery = Schemas["PairQuery"];
export type PairwiseNext = Schemas["PairwiseNext"];
export type AgentOut = Schemas["AgentOut"];
export type TrainingPoint = Schemas["TrainingPointOut"];
export type TrainingCurve = Schemas["TrainingCurve"];
export type EnvInfo = Schemas["EnvOut"];
/** The server's OpenAPI document, as far as the New-session form reads it. */
export interface OpenApiDocument {
  components: { schemas: Record<string, JsonSchema> };
}
/** More training for a finished session: exactly one of the two. */
export type ContinueIn = { steps: number; rounds?: never } | { rounds: number; steps?: never };
export type Phase = SessionState["phase"];
export type Label = JudgementIn["label"];

export const STALE: unique symbol = Symbol("stale response");
export type Stale = typeof STALE;

/** A failed request, with a message fit to show as it is. */
export class ApiError extends Error {
  constructor(
    readonly status: number,
    message: string,
    /** True when the server could not be reached at all. */
    readonly network = false,
  ) {
    super(message);
    this.name = "ApiError";
  }
}

const NETWORK_MESSAGE =
  "Cannot reach the groupwise server; check that `groupwise serve` is still running.";

const STATUS_MESSAGES: Record<number, string> = {
  403: "Only the session's owner can do this.",
  401: "Access denied: open the page with the ?token= that `groupwise serve` printed.",
  404: "Not found on the server.",
  409: "The session is not in a state that allows this right now.",
  413: "The request is too large (over 1 MiB).",
  422: "The server rejected the request as invalid.",
};

interface ValidationItem {
  loc?: unknown[];
  msg?: string;
}

/** One clear sentence from an error response's status and (parsed JSON) body. */
export function errorMessage(status: number, body: unknown): string {
  const detail = (body as { detail?: unknown } | null)?.detail;
  if (typeof detail === "string" && detail.trim()) return detail;
  if (Array.isArray(detail) && detail.length > 0) {
    // FastAPI's 422: [{loc: ["body", "settings", "pool_size"], msg: "…"}, …]
    return (detail as ValidationItem[])
      .map((item) => {
        const loc = (item.loc ?? []).filter((p, i) => !(i === 0 && isSource(p)));
        const where = loc.join(".");
        const msg = item.msg ?? "invalid";
        return where ? `${where}: ${msg}` : msg;
      })
      .join("; ");
  }
  if (status >= 500) return `The server failed (${status}); see its log for the cause.`;
  return STATUS_MESSAGES[status] ?? `The request failed (${status}).`;
}

function isSource(p: unknown): boolean {
  return p === "body" || p === "query" || p === "path" || p === "header";
}

export interface ApiOptions {
  /** Base URL the paths `api/…` and `clips/…` resolve against; default the page's base. */
  base?: string;
  /** Access token (`?token=` of the page), sent as a Bearer header and on clip/event URLs. */
  token?: string | null;
  fetch?: typeof fetch;
  EventSource?: typeof EventSource;
  /** Waits between judgement retries (ms); injectable for tests. */
  retryDelays?: readonly number[];
  sleep?: (ms: number) => Promise<void>;
}

/** The session's revision an event was sent at (its SSE `id:`), null when it had none. */
export type Revision = number | null;

export interface EventHandlers {
  state?(state: SessionState, rev: Revision): void;
  judgement?(judgement: JudgementOut, rev: Revision): void;
  round?(event: { round: number }): void;
  /** A point of the agent's learning curve the worker wrote. */
  training?(point: TrainingPoint): void;
  open?(): void;
  /** The stream dropped; EventSource reconnects by itself. */
  error?(): void;
}

type Query = Record<string, string | number | readonly string[] | undefined>;

interface RequestInit_ {
  body?: unknown;
  query?: Query;
}

const RETRY_STATUS = new Set([502, 503, 504]);

export function createApi(options: ApiOptions = {}) {
  const doFetch = options.fetch ?? globalThis.fetch.bind(globalThis);
  const base = options.base ?? globalThis.document?.baseURI ?? "http://localhost/";
  const token = options.token ?? null;
  const retryDelays = options.retryDelays ?? [400, 1200, 3000];
  const sleep = options.sleep ?? ((ms: number) => new Promise<void>((r) => setTimeout(r, ms)));
  const latest = new Latest();

  function url(path: string, query: Query = {}, withToken = false): string {
    const u = new URL(path, base);
    for (const [key, value] of Object.entries(query)) {
      if (value === undefined) continue;
      if (Array.isArray(value)) for (const v of value) u.searchParams.append(key, String(v));
      else u.searchParams.set(key, String(value));
    }
    if (withToken && token) u.searchParams.set("token", token);
    return u.toString();
  }

  async function request<T>(method: string, path: string, init: RequestInit_ = {}): Promise<T> {
    const headers: Record<string, string> = { Accept: "application/json" };
    if (init.body !== undefined) headers["Content-Type"] = "application/json";
    if (token) headers.Authorization = `Bearer ${token}`;
    let response: Response;
    try {
      response = await doFetch(url(path, init.query), {
        method,
        headers,
        body: init.body === undefined ? undefined : JSON.stringify(init.body),
      });
    } catch {
      throw new ApiError(0, NETWORK_MESSAGE, true);
    }
    let body: unknown = null;
    const text = await response.text().catch(() => "");
    if (text) {
      try {
        body = JSON.parse(text);
      } catch {
        body = null;
      }
    }
    if (!response.ok) throw new ApiError(response.status, errorMessage(response.status, body));
    return body as T;
  }

  /** A read that resolves to STALE when the resource moved on before it answered. */
  async function read<T>(resource: string, method: string, path: string, init?: RequestInit_) {
    const ticket = latest.take(resource);
    try {
      const value = await request<T>(method, path, init);
      return latest.isCurrent(resource, ticket) ? value : STALE;
    } catch (err) {
      if (!latest.isCurrent(resource, ticket)) return STALE;
      throw err;
    }
  }

  const s = (sid: string) => `api/sessions/${encodeURIComponent(sid)}`;

  return {
    invalidate: (resource: string) => latest.invalidate(resource),

    envs: () => request<EnvInfo[]>("GET", "api/envs"),
    sessions: () => request<SessionState[]>("GET", "api/sessions"),
    createSession: (body: SessionCreate) => request<SessionState>("POST", "api/sessions", { body }),
    /** The server's schema: the New-session form's fields come from its `SessionSettings`. */
    openapi: () => request<OpenApiDocument>("GET", "api/openapi.json"),
    /** The settings creating a session with `body` would store (422: why it would refuse);
     * STALE when a newer check was issued meanwhile. */
    resolveSettings: (body: SessionCreate) =>
      read<Settings>("settings", "POST", "api/settings/resolve", { body }),

    session: (sid: string) => read<SessionState>("session", "GET", s(sid)),
    tree: (sid: string, round: number) =>
      read<RoundTree>("tree", "GET", `${s(sid)}/rounds/${round}/tree`),
    edges: (sid: string, round: number, k: number) =>
      read<Edge[]>("edges", "GET", `${s(sid)}/rounds/${round}/edges`, { query: { k } }),
    judgements: (sid: string, round: number) =>
      read<JudgementOut[]>("judgements", "GET", `${s(sid)}/judgements`, { query: { round } }),
    /** `exclude`: suggestions to pass over, each as its [left ids, right ids]. */
    nextSuggestion: (sid: string, round: number, exclude: ReadonlyArray<readonly [string[], string[]]> = []) =>
      read<{ suggestion: Suggestion | null }>(
        "suggestion",
        "POST",
        `${s(sid)}/rounds/${round}/next-suggestion`,
        { body: exclude.length ? { exclude: exclude.flat() } : {} },
      ),
    pairwiseNext: (sid: string) => read<PairwiseNext>("pairwise", "GET", `${s(sid)}/pairwise/next`),
    /** Skips a pair for the rest of the round; answers the next pairs like `pairwiseNext`. */
    skipPair: (sid: string, pair: { left: string; right: string }) =>
      read<PairwiseNext>("pairwise", "POST", `${s(sid)}/pairwise/skip`, {
        body: { left: pair.left, right: pair.right },
      }),

    async submitJudgement(sid: string, body: JudgementIn): Promise<JudgementOut> {
      for (let attempt = 0; ; attempt++) {
        try {
          return await request<JudgementOut>("POST", `${s(sid)}/judgements`, { body });
        } catch (err) {
          const retriable =
            err instanceof ApiError && (err.network || RETRY_STATUS.has(err.status));
          if (!retriable || attempt >= retryDelays.length) throw err;
          await sleep(retryDelays[attempt]!);
        }
      }
    },
    undoJudgement: (sid: string, id: number) =>
      request<JudgementOut>("DELETE", `${s(sid)}/judgements/${id}`),

    /** The session's people with their counters and agreement (the owner first). */
    annotators: (sid: string) => read<Annotator[]>("annotators", "GET", `${s(sid)}/annotators`),
    /** The owner adds a person by name: their link (with their token) is in the answer only. */
    addAnnotator: (sid: string, name: string) =>
      request<AnnotatorCreated>("POST", `${s(sid)}/annotators`, { body: { name } }),
    /** The owner removes a person: their link stops working; their judgements stay. */
    removeAnnotator: (sid: string, aid: string) =>
      request<null>("DELETE", `${s(sid)}/annotators/${encodeURIComponent(aid)}`),

    /** pause, resume, end-round, retry: the reply is newer than any session read in flight. */
    async control(sid: string, action: "pause" | "resume" | "end-round" | "retry") {
      const state = await request<SessionState>("POST", `${s(sid)}/${action}`);
      latest.invalidate("session");
      return state;
    },

    /** No more rounds after the current one; then the final phase. */
    async finish(sid: string) {
      const state = await request<SessionState>("POST", `${s(sid)}/finish`);
      latest.invalidate("session");
      return state;
    },

    /** A finished session trains again: more PPO steps, or more rounds. */
    async continueTraining(sid: string, body: ContinueIn) {
      const state = await request<SessionState>("POST", `${s(sid)}/continue`, { body });
      latest.invalidate("session");
      return state;
    },

    /** The finished session's agent (409 before it is finished, 404 when it has none). */
    agent: (sid: string) => read<AgentOut>("agent", "GET", `${s(sid)}/agent`),

    /** Round `round`'s policy becomes the take-away agent (the download, its summary and
     * video): 404 for no such round, 409 before the session is finished or when the round's
     * checkpoint is gone (the reason in the message). */
    async pickAgent(sid: string, round: number) {
      const agent = await request<AgentOut>("PUT", `${s(sid)}/agent/round`, { body: { round } });
      latest.invalidate("agent");
      return agent;
    },

    /** The session's learning curve: PPO steps, true returns, refits, the pool's age. */
    training: (sid: string) => read<TrainingCurve>("training", "GET", `${s(sid)}/training`),

    /** The page shows the open round `round` (its timer starts the first time). */
    async shown(sid: string, round: number) {
      const state = await request<SessionState>("POST", `${s(sid)}/rounds/${round}/shown`);
      latest.invalidate("session");
      return state;
    },

    clipUrl: (clip: string) => url(`clips/${encodeURIComponent(clip)}`, {}, true),
    exportUrl: (sid: string, format: "jsonl" | "parquet" = "jsonl") =>
      url(`${s(sid)}/export`, { format }, true),
    /** The final agent's video; `round` names the agent, so a newer one is fetched anew. */
    agentVideoUrl: (sid: string, round: number) => url(`${s(sid)}/agent.mp4`, { v: round }, true),
    agentZipUrl: (sid: string, round: number) => url(`${s(sid)}/agent.zip`, { v: round }, true),
    /** Round `round`'s greedy policy filmed for one episode (the clips the agent is picked by). */
    agentRoundVideoUrl: (sid: string, round: number) =>
      url(`${s(sid)}/agent/rounds/${round}.mp4`, {}, true),

    /** Subscribes to the session's event stream; returns a function that closes it. */
    events(sid: string, handlers: EventHandlers): () => void {
      const ES = options.EventSource ?? globalThis.EventSource;
      const source = new ES(url(`${s(sid)}/events`, {}, true));
      const on = <T>(name: string, fn: ((data: T, rev: Revision) => void) | undefined) => {
        source.addEventListener(name, (event) => {
          const message = event as MessageEvent<string>;
          let data: T;
          try {
            data = JSON.parse(message.data) as T;
          } catch {
            return; // a malformed event is not worth breaking the page for
          }
          const rev = Number.parseInt(message.lastEventId ?? "", 10);
          fn?.(data, Number.isFinite(rev) ? rev : null);
        });
      };
      on<SessionState>("state", (state, rev) => {
        latest.invalidate("session");
        latest.invalidate("annotators");
        handlers.state?.(state, rev);
      });
      on<JudgementOut>("judgement", (judgement, rev) => {
        // A read of the people sent before this judgement misses it.
        latest.invalidate("annotators");
        handlers.judgement?.(judgement, rev);
      });
      on("round", handlers.round);
      on("training", handlers.training);
      source.onopen = () => handlers.open?.();
      source.onerror = () => handlers.error?.();
      return () => source.close();
    },
  };
}

export type Api = ReturnType<typeof createApi>;
