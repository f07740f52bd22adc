/**
 * The page: mounts the views, derives each view's data from the one store (once per frame),
 * and maps keys and handlers to store actions and controller effects.
 */
import { type Annotator, type Api, type Edge, type JudgementOut, createApi } from "./api";
import { type Controller, createController } from "./controller";
import { OWNER_COLOUR, OWNER_ID, annotatorColours, isShared, judgementAnnotator, meOf } from "./lib/annotators";
import { clipCaption } from "./lib/clip-timing";
import { outward } from "./lib/centre";
import { guideSeen, rememberGuideSeen } from "./lib/guide";
import { type KeyInput, keyCommand } from "./lib/keys";
import type { Tree } from "./lib/tree";
import { type State, type Store, comparedLeaves, createStore } from "./state";
import { startTogether } from "./views/clips";
import { type ClipRef, renderComparison } from "./views/comparison";
import { h } from "./views/dom";
import { type HistoryEdge, renderExploration } from "./views/exploration";
import { renderAnnotatorsDialog } from "./views/annotators-dialog";
import { renderGuide } from "./views/guide";
import { renderPeople } from "./views/people";
import { renderPairwise } from "./views/pairwise";
import { renderProgress } from "./views/progress";
import { renderResults } from "./views/results";
import { renderTraining } from "./views/training";
import { renderStart } from "./views/start";
import { renderStatus } from "./views/status";
import { renderToast } from "./views/toast";

/** Caches a function of one argument by the argument's identity (derived data per state). */
function memo1<A, R>(fn: (a: A) => R): (a: A) => R {
  let last: { a: A; r: R } | null = null;
  return (a) => {
    if (!last || last.a !== a) last = { a, r: fn(a) };
    return last.r;
  };
}

function memo2<A, B, R>(fn: (a: A, b: B) => R): (a: A, b: B) => R {
  let last: { a: A; b: B; r: R } | null = null;
  return (a, b) => {
    if (!last || last.a !== a || last.b !== b) last = { a, b, r: fn(a, b) };
    return last.r;
  };
}

const historyEdges = memo1((judgements: readonly JudgementOut[]): HistoryEdge[] =>
  judgements.flatMap((j) => j.pairs.map((p) => ({ a: p.a, b: p.b, label: p.label }))),
);
const compared = memo1(comparedLeaves);
/** A colour per person: the session's list in its order, then anyone only judgements name. */
const colours = memo2((people: readonly Annotator[], judgements: readonly JudgementOut[]) =>
  annotatorColours([...people.map((p) => p.id), ...judgements.map((j) => judgementAnnotator(j).id)]),
);
const topK = memo2((edges: readonly Edge[], k: number) => edges.slice(0, Math.max(0, k)));
const highlighted = memo2((hover: State["hover"], tree: Tree | undefined): ReadonlySet<string> => {
  const node = hover.id ? tree?.nodes.get(hover.id) : undefined;
  return new Set(node?.leaves ?? []);
});

export interface AppOptions {
  api?: Api;
  store?: Store;
  /** The page's query string (session, token, annotator). */
  search?: string;
}

/** The key hint of the message bar, per mode. */
const KEYS_HINT = {
  groupwise:
    "Keys: ← A better · → B better · ↑ equal · N next suggestion · U undo · G switch group · " +
    "Shift + arrows move through the chart · Enter selects · C centres · Esc out · ? guide",
  pairwise: "Keys: ← left better · → right better · ↑ equal · ↓ skip · U undo · ? guide",
} as const;

function localStore(): Storage | null {
  try {
    return globalThis.localStorage ?? null;
  } catch {
    return null; // storage disabled by the browser
  }
}

export function startApp(root: HTMLElement, options: AppOptions = {}): { store: Store; controller: Controller } {
  const params = new URLSearchParams(options.search ?? window.location.search);
  const api = options.api ?? createApi({ token: params.get("token") });
  const store = options.store ?? createStore();
  const controller = createController(store, api, {
    annotator: params.get("annotator") ?? "",
    setUrl(sid) {
      const url = new URL(window.location.href);
      url.searchParams.delete("new"); // a reload shows the session, not the form again
      if (sid) url.searchParams.set("session", sid);
      else url.searchParams.delete("session");
      window.history.replaceState(null, "", url);
    },
  });
  const dispatch = store.dispatch;

  const status = h("header", { class: "statusbar", hidden: true });
  const start = h("section", { class: "start", hidden: true });
  const message = h("div", { class: "page-message", role: "status" });
  const exploration = h("section", {});
  const comparison = h("section", {});
  const progressA = h("div", { class: "progress-overlay", hidden: true });
  const pairwise = h("section", {});
  const progressB = h("div", { class: "progress-overlay", hidden: true });
  // The agent learning (a continuous session): under the comparison, or under the pair.
  const trainingA = h("section", { hidden: true });
  const trainingB = h("section", { hidden: true });
  // The people of a shared session: likewise under the comparison, or under the pair.
  const peopleA = h("section", { hidden: true });
  const peopleB = h("section", { hidden: true });
  // The chart keeps the left column's height (issue 40: at least 60 % of a 768 px screen);
  // the learning and people panels go under the comparison.
  const groupWorkspace = h(
    "div",
    { class: "workspace groupwise", hidden: true },
    h("div", { class: "left" }, exploration),
    h("div", { class: "right" }, h("div", { class: "compare-stack" }, comparison, progressA), trainingA, peopleA),
  );
  const pairWorkspace = h(
    "div",
    { class: "workspace pairwise-mode", hidden: true },
    h("div", { class: "right" }, pairwise, progressB),
    trainingB,
    peopleB,
  );
  // The finished session's agent: its video, chart, downloads (in place of the workspace).
  const results = h("section", { hidden: true, "aria-label": "Session results" });
  // The message bar: the key hint, and the toasts (confirmations, errors) in a strip of
  // their own, so they never cover a control (docs/app.md).
  const toast = h("div", { class: "toast-host" });
  const keysHint = h("p", { class: "keys-hint", "aria-hidden": "true" });
  const messageBar = h("footer", { class: "messagebar" }, keysHint, toast);
  const guide = h("div", {});
  const peopleDialog = h("div", { hidden: true });
  const main = h("main", { class: "main" }, message, start, groupWorkspace, pairWorkspace, results);
  root.replaceChildren(status, main, messageBar, guide, peopleDialog);
  const guideStorage = localStore();
  /** Modes whose guide this page already offered (it opens by itself once per mode). */
  const offered = new Set<string>();

  function closeGuide(): void {
    const mode = store.getState().session?.mode;
    if (mode) rememberGuideSeen(guideStorage, mode);
    dispatch({ type: "guide", open: false });
    void controller.reportShown();
  }

  const clipsOf = memo1((tree: Tree | undefined) => (id: string): ClipRef | null => {
    const leaf = tree?.nodes.get(id);
    if (!leaf?.clip) return null;
    const ref: ClipRef = { src: api.clipUrl(leaf.clip) };
    if (leaf.poster) ref.poster = api.clipUrl(leaf.poster);
    return ref;
  });

  function render(): void {
    const st = store.getState();
    const s = st.session;
    const mode = st.boot === "ready" && s ? s.mode : null;
    message.hidden = st.boot === "ready" || st.boot === "choose";
    message.textContent =
      st.boot === "error" ? `Cannot load the app: ${st.bootError ?? "unknown error"}` : "Loading…";
    message.classList.toggle("error", st.boot === "error");
    start.hidden = st.boot !== "choose";
    const agent = s?.phase === "finished" && st.agent?.key === `${s.id}:${s.round}` ? st.agent.data : null;
    results.hidden = !mode || !agent;
    if (results.hidden) results.querySelector("video")?.pause();
    groupWorkspace.hidden = mode !== "groupwise" || !results.hidden;
    pairWorkspace.hidden = mode !== "pairwise" || !results.hidden;
    status.hidden = !s || st.boot !== "ready";

    if (st.boot === "choose") {
      const data = { envs: st.envs, schemas: st.schemas, newSession: st.newSession, sessions: st.sessions, busy: st.busy };
      renderStart(start, data, {
        open: (sid) => void controller.open(sid),
        check: (body) => void controller.checkNewSession(body),
        create: (body) => void controller.create(body),
      });
    }
    const me = meOf(s);
    const shared = isShared(s);
    const people = st.annotators.list;
    const colourOf = colours(people, st.judgements);
    if (s && st.boot === "ready") {
      const statusData = {
        session: s,
        sessionAt: st.sessionAt,
        connection: st.connection,
        busy: st.busy,
        me,
        shared,
        annotators: people.filter((p) => p.id !== OWNER_ID).length,
        colour: colourOf.get(me.id) ?? OWNER_COLOUR,
      };
      renderStatus(status, statusData, {
        pause: () => void controller.control("pause"),
        resume: () => void controller.control("resume"),
        endRound: () => void controller.control("end-round"),
        finish: () => void controller.finish(),
        sessions: () => void controller.showStart(),
        guide: () => dispatch({ type: "guide", open: true }),
        people: () => {
          dispatch({ type: "people", patch: { open: !st.people.open, error: null } });
          if (!st.people.open) void controller.refreshAnnotators();
        },
      });
      const progress = { session: s, exportUrl: api.exportUrl(s.id), busy: st.busy, owner: me.owner };
      if (agent && mode) {
        renderResults(
          results,
          {
            session: s,
            agent,
            videoUrl: api.agentVideoUrl(s.id, agent.round),
            downloadUrl: api.agentZipUrl(s.id, agent.round),
            exportUrl: progress.exportUrl,
            roundVideoUrl: (round) => api.agentRoundVideoUrl(s.id, round),
            busy: st.busy,
            owner: me.owner,
            training: st.training?.sid === s.id ? st.training.points : [],
          },
          {
            continueTraining: (body) => void controller.continueTraining(body),
            pickAgent: (round) => controller.pickAgent(round),
          },
        );
      }
      const retry = { retry: () => void controller.control("retry") };
      const points = st.training?.sid === s.id ? st.training.points : [];
      const target = st.envs.find((e) => e.name === s.env)?.target ?? null;
      renderTraining(mode === "groupwise" ? trainingA : trainingB, { session: s, points, target });
      if (mode) {
        renderPeople(mode === "groupwise" ? peopleA : peopleB, {
          shared: shared && results.hidden,
          people,
          meId: me.id,
          colours: colourOf,
          judgements: st.judgements,
          mode,
          round: s.round,
        });
      }
      if (mode === "groupwise") {
        renderGroupwise(st);
        renderProgress(progressA, progress, retry);
      } else {
        renderPair(st);
        renderProgress(progressB, progress, retry);
      }
    }
    renderToast(toast, st.toast, st.judgements.length > 0 && s?.phase === "ready", {
      dismiss: (id) => dispatch({ type: "dismiss-toast", id }),
      undo: () => void controller.undo(),
    });
    // The finished page answers nothing: no answer keys to hint at.
    const hint = mode && results.hidden ? KEYS_HINT[mode] : "";
    if (keysHint.textContent !== hint) {
      keysHint.textContent = hint;
      keysHint.title = hint;
    }
    renderGuide(guide, mode, st.guide && mode !== null, { close: closeGuide });
    renderAnnotatorsDialog(
      peopleDialog,
      { open: st.people.open && me.owner && !!s, people, colours: colourOf, state: st.people, base: document.baseURI },
      {
        add: (name) => controller.addAnnotator(name),
        remove: (id) => void controller.removeAnnotator(id),
        close: closePeople,
      },
    );
  }

  function closePeople(): void {
    dispatch({ type: "people", patch: { open: false, created: null, error: null } });
    status.querySelector<HTMLElement>(".people-button")?.focus();
  }

  function renderGroupwise(st: State): void {
    const s = st.session!;
    const round = st.round;
    const open = s.phase === "ready" && round !== null && round.round === s.round;
    const placeholder =
      s.phase === "preparing"
        ? `The behaviours of round ${s.round} are being prepared…`
        : s.phase === "failed"
          ? "No behaviours to show: the worker failed."
          : "Loading the behaviours…";
    renderExploration(
      exploration,
      {
        round,
        placeholder,
        groups: st.groups,
        target: st.target,
        hover: st.hover,
        centre: st.centre,
        suggestions: topK(st.suggestions, st.view.k),
        maxK: st.suggestions.length,
        history: historyEdges(st.judgements),
        compared: compared(st.judgements),
        view: st.view,
        clipUrl: api.clipUrl,
      },
      {
        select: (click, other) => dispatch({ type: "select", click, other, at: Date.now() }),
        hover: (id) => dispatch({ type: "hover", id, from: id ? "chart" : null }),
        centre: (id) => dispatch({ type: "centre", id }),
        target: (group) => dispatch({ type: "target", group }),
        view: (patch) => dispatch({ type: "view", patch }),
      },
    );
    const { A, B } = st.groups;
    const hint = !open
      ? "The round is not open for answers."
      : st.submitting
        ? "Saving your answer…"
        : !A.length && !B.length
          ? "Fill both groups to answer."
          : !A.length
            ? "Fill group A to answer."
            : !B.length
              ? "Fill group B to answer."
              : "";
    renderComparison(
      comparison,
      {
        groups: st.groups,
        target: st.target,
        clipOf: clipsOf(round?.tree),
        highlighted: highlighted(st.hover, round?.tree),
        speed: st.view.speed,
        clipCaption: clipCaption(round?.clip, st.view.speed),
        canAnswer: hint === "",
        answerHint: hint,
        submitting: st.submitting,
        origin: st.origin,
        suggestionStatus: st.suggestionStatus,
        canSuggest: open,
        canUndo: open && st.judgements.length > 0,
        undoing: st.undoing,
      },
      {
        remove: (id) => dispatch({ type: "remove", id, at: Date.now() }),
        move: (id) => dispatch({ type: "move", id, at: Date.now() }),
        hover: (id) => dispatch({ type: "hover", id, from: id ? "clip" : null }),
        answer: (label) => void controller.answer(label),
        next: () => void controller.suggest(false),
        clear: () => dispatch({ type: "clear" }),
        undo: () => void controller.undo(),
        speed: (rate) => dispatch({ type: "view", patch: { speed: rate } }),
        target: (group) => dispatch({ type: "target", group }),
        restart: () => void startTogether([...comparison.querySelectorAll("video")], st.view.speed),
      },
    );
  }

  function renderPair(st: State): void {
    const s = st.session!;
    const open = s.phase === "ready";
    const pw = st.pairwise;
    renderPairwise(
      pairwise,
      {
        current: pw.current,
        following: pw.following,
        clipUrl: api.clipUrl,
        canAnswer: open && pw.current !== null,
        hint: open ? "" : "The round is not open for answers.",
        submitting: st.submitting,
        loading: pw.loading,
        exhausted: pw.exhausted,
        canUndo: open && st.judgements.length > 0 && !st.undoing,
        speed: st.view.speed,
        clipCaption: clipCaption(pw.clip, st.view.speed),
      },
      {
        answer: (label) => controller.answerPair(label),
        skip: () => controller.skipPair(),
        undo: () => void controller.undo(),
        speed: (rate) => dispatch({ type: "view", patch: { speed: rate } }),
      },
    );
  }

  // The guide opens by itself the first time a mode is opened in this browser.
  store.subscribe((st) => {
    const mode = st.boot === "ready" ? st.session?.mode : undefined;
    if (!mode || offered.has(mode)) return;
    offered.add(mode);
    if (!guideSeen(guideStorage, mode)) dispatch({ type: "guide", open: true });
  });
  document.addEventListener("visibilitychange", () => void controller.reportShown());

  let frame = 0;
  store.subscribe(() => {
    if (!frame) frame = requestAnimationFrame(() => {
      frame = 0;
      render();
    });
  });

  document.addEventListener("keydown", (e) => {
    const st = store.getState();
    const s = st.session;
    if (st.boot !== "ready" || !s) return;
    if (st.people.open) {
      // The owner's dialog: the answer keys rest while it is open.
      if (e.key === "Escape") {
        e.preventDefault();
        closePeople();
      }
      return;
    }
    if (st.guide) {
      // A dialog: the answer keys rest until it is closed.
      if (e.key === "Escape") {
        e.preventDefault();
        closeGuide();
      }
      return;
    }
    const target = e.target as HTMLElement | null;
    const input: KeyInput = {
      key: e.key,
      ctrlKey: e.ctrlKey,
      metaKey: e.metaKey,
      altKey: e.altKey,
      shiftKey: e.shiftKey,
      repeat: e.repeat,
      inField: !!target?.closest?.("input, select, textarea, [contenteditable]"),
    };
    const cmd = keyCommand(input, s.mode);
    if (!cmd) return;
    e.preventDefault();
    switch (cmd.type) {
      case "answer":
        if (s.mode === "pairwise") controller.answerPair(cmd.label);
        else void controller.answer(cmd.label);
        break;
      case "skip":
        controller.skipPair();
        break;
      case "undo":
        void controller.undo();
        break;
      case "switch-group":
        dispatch({ type: "target", group: "switch" });
        break;
      case "target":
        dispatch({ type: "target", group: cmd.group });
        break;
      case "next-suggestion":
        void controller.suggest(false);
        break;
      case "guide":
        dispatch({ type: "guide", open: true });
        break;
      case "out": {
        const tree = st.round?.tree;
        if (tree && st.centre !== null) dispatch({ type: "centre", id: outward(tree, st.centre) });
        break;
      }
    }
  });

  render();
  void controller.boot(params.get("session"), params.has("new"));
  return { store, controller };
}
