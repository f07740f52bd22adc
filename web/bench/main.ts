/**
 * Dev-only entry (bench.html, built by `npm run build:bench`, never shipped in dist/):
 * - default: `window.bench.run(n)` times the exploration view on a synthetic round
 *   (benchmarks/web_render.py drives it in Chromium);
 * - `?demo=groupwise` / `?demo=pairwise`: the whole app on an in-memory fake server
 *   (`&n=1000` behaviours; `&clips=served`: clips and posters as files under clips/;
 *   `&shared=owner` / `&shared=annotator`: a session shared by three people, seen by its
 *   owner or by one of them; `&owner=NAME` names the owner; `&training=continuous`: the
 *   learning panel of a continuously training session).
 */
import "../src/styles.css";
import { STALE, type SessionState } from "../src/api";
import { startApp } from "../src/app";
import { DEFAULT_BETA } from "../src/lib/edges";
import { guideKey } from "../src/lib/guide";
import { type Groups, EMPTY_GROUPS } from "../src/lib/selection";
import { buildTree } from "../src/lib/tree";
import { comparedLeaves } from "../src/state";
import type { RoundData } from "../src/state";
import { type ExplorationData, type ExplorationHandlers, renderExploration } from "../src/views/exploration";
import { fakeApi } from "./fake-api";
import { rng, syntheticRound } from "./synthetic";

const params = new URLSearchParams(window.location.search);
const demo = params.get("demo");

const frame = () => new Promise<number>((r) => requestAnimationFrame((t) => r(t)));
const afterPaint = () => new Promise<void>((r) => requestAnimationFrame(() => setTimeout(r, 0)));

function quantile(xs: number[], q: number): number {
  const s = [...xs].sort((a, b) => a - b);
  return s[Math.min(s.length - 1, Math.floor(q * s.length))] ?? Number.NaN;
}

export interface BenchResult {
  leaves: number;
  arcs: number;
  suggestions: number;
  history: number;
  /** Synchronous render + style/layout flush of the first render (ms). */
  firstRenderMs: number;
  /** From the start of the first render to after the next frame was painted (ms). */
  firstPaintMs: number;
  /** … to after the frame with the edges (drawn one frame after the arcs) was painted. */
  edgesPaintMs: number;
  updateMedianMs: number;
  updateP95Ms: number;
  hoverMedianMs: number;
  /** Mean interval between frames with one selection update per frame (ms). */
  frameMs: number;
  /** The same with one hover (edge highlight) per frame. */
  hoverFrameMs: number;
  /** A wheel event's zoom step (d3-zoom's transform onto the layers' CSS transform) plus
   * style/layout, median and 95th percentile (ms). */
  zoomStepMedianMs: number;
  zoomStepP95Ms: number;
  /** Mean interval between frames with one wheel step per frame, zooming in to ×5.5 and
   * back out (ms): the drawn layers move under a CSS transform. */
  zoomFrameMs: number;
  /** From the gesture's end to the frame with the arcs and edges drawn afresh at its zoom
   * painted (ms; mean of the zoom in and the zoom out). */
  zoomSettleMs: number;
}

async function run(n: number, suggestions = 100, history = 400, updates = 40): Promise<BenchResult> {
  const synth = syntheticRound(n, { suggestions, history, seed: n });
  const host = document.getElementById("app")!;
  host.replaceChildren();
  await afterPaint();
  const element = document.createElement("section");
  // The left column of the app at 1366 × 768.
  element.style.cssText = "position: fixed; left: 12px; top: 60px; bottom: 12px; width: 640px;";
  host.append(element);
  const round: RoundData = { sid: "bench", round: 0, tree: buildTree(synth.tree, synth.levels), medoids: synth.medoids };
  let data: ExplorationData = {
    round,
    placeholder: "",
    groups: EMPTY_GROUPS,
    target: "A",
    hover: { id: null, from: null },
    centre: null,
    suggestions: synth.suggestions,
    maxK: synth.suggestions.length,
    history: synth.judgements.flatMap((j) => j.pairs),
    compared: comparedLeaves(synth.judgements),
    view: { showSuggestions: true, showHistory: true, k: suggestions, beta: DEFAULT_BETA, speed: 1 },
    clipUrl: (c) => c,
  };
  const handlers: ExplorationHandlers = { select() {}, hover() {}, centre() {}, target() {}, view() {} };
  const flush = () => void document.body.offsetHeight;

  const t0 = performance.now();
  renderExploration(element, data, handlers);
  flush();
  const firstRenderMs = performance.now() - t0;
  await afterPaint();
  const firstPaintMs = performance.now() - t0;
  const canvas = element.querySelector("canvas")!;
  while (!canvas.dataset.drawnAt) await frame();
  await afterPaint();
  const edgesPaintMs = performance.now() - t0;

  const rand = rng(7);
  const cands = synth.candidates;
  const groupsAt = (): Groups => {
    const a = cands[Math.floor(rand() * cands.length)]!.leaves;
    const b = cands[Math.floor(rand() * cands.length)]!.leaves.filter((x) => !a.includes(x));
    return { A: a, B: b };
  };
  const times: number[] = [];
  for (let i = 0; i < updates; i++) {
    data = { ...data, groups: groupsAt() };
    const t = performance.now();
    renderExploration(element, data, handlers);
    flush();
    times.push(performance.now() - t);
    await frame();
  }
  const hovers: number[] = [];
  for (let i = 0; i < 20; i++) {
    const id = synth.leaves[Math.floor(rand() * n)]!;
    data = { ...data, hover: { id, from: "chart" } };
    const t = performance.now();
    renderExploration(element, data, handlers);
    flush();
    hovers.push(performance.now() - t);
    await frame();
  }
  data = { ...data, hover: { id: null, from: null } };
  // One update per frame: the mean frame interval shows whether updates fit in a frame.
  const stamps: number[] = [await frame()];
  for (let i = 0; i < 30; i++) {
    data = { ...data, groups: groupsAt() };
    renderExploration(element, data, handlers);
    stamps.push(await frame());
  }
  const frameMs = (stamps[stamps.length - 1]! - stamps[0]!) / (stamps.length - 1);
  const hoverStamps: number[] = [await frame()];
  for (let i = 0; i < 30; i++) {
    const id = synth.leaves[Math.floor(rand() * n)]!;
    data = { ...data, hover: { id, from: "chart" } };
    renderExploration(element, data, handlers);
    hoverStamps.push(await frame());
  }
  const hoverFrameMs = (hoverStamps[hoverStamps.length - 1]! - hoverStamps[0]!) / (hoverStamps.length - 1);
  data = { ...data, hover: { id: null, from: null } };
  renderExploration(element, data, handlers);
  await frame();
  // Zoom (issue 40): one wheel step per frame on the chart, in towards the top of the ring
  // and back out, as a person's wheel or pinch sends them.
  const svg = element.querySelector<SVGSVGElement>(".chart-svg")!;
  const box = svg.getBoundingClientRect();
  const at = { clientX: box.x + box.width / 2, clientY: box.y + box.height * 0.2 };
  const wheel = (deltaY: number) =>
    svg.dispatchEvent(new WheelEvent("wheel", { ...at, deltaY, deltaMode: 0, bubbles: true, cancelable: true }));
  const wrap = element.querySelector<HTMLElement>(".chart-wrap")!;
  const zoomSteps: number[] = [];
  const zoomFrames: number[] = [];
  const settles: number[] = [];
  for (const deltaY of [-40, 40]) {
    const stamps = [await frame()];
    for (let i = 0; i < 30; i++) {
      const t = performance.now();
      wheel(deltaY);
      flush();
      zoomSteps.push(performance.now() - t);
      stamps.push(await frame());
    }
    zoomFrames.push((stamps[stamps.length - 1]! - stamps[0]!) / (stamps.length - 1));
    // d3-zoom ends a wheel gesture 150 ms after its last step; then arcs and edges are
    // drawn afresh at the new zoom.
    const before = wrap.dataset.settledAt;
    while (wrap.dataset.settledAt === before) await frame();
    const settledAt = Number(wrap.dataset.settledAt);
    while (Number(canvas.dataset.drawnAt) < settledAt) await frame();
    await afterPaint();
    settles.push(performance.now() - settledAt);
  }
  const zoomFrameMs = (zoomFrames[0]! + zoomFrames[1]!) / 2;
  return {
    leaves: n,
    arcs: element.querySelectorAll(".arc").length,
    suggestions: Number(element.querySelector("canvas")?.dataset.suggestions ?? 0),
    history: Number(element.querySelector("canvas")?.dataset.history ?? 0),
    firstRenderMs,
    firstPaintMs,
    edgesPaintMs,
    updateMedianMs: quantile(times, 0.5),
    updateP95Ms: quantile(times, 0.95),
    hoverMedianMs: quantile(hovers, 0.5),
    frameMs,
    hoverFrameMs,
    zoomStepMedianMs: quantile(zoomSteps, 0.5),
    zoomStepP95Ms: quantile(zoomSteps, 0.95),
    zoomFrameMs,
    zoomSettleMs: (settles[0]! + settles[1]!) / 2,
  };
}

export interface AppBenchResult {
  leaves: number;
  /** From starting the app on the fake server to the frame with arcs and edges painted (ms). */
  onScreenMs: number;
  /** A click that fills a group: the app's render in the next frame plus style/layout (ms). */
  selectMedianMs: number;
  selectP95Ms: number;
  /** A pointer entering a leaf arc: the same for the hover render (ms). */
  hoverMedianMs: number;
  /** Video elements on the page once the round is on screen (clips load lazily: 0). */
  videosAtLoad: number;
  /** The most video elements with a source at any moment of the run. */
  videosMax: number;
  /** Video elements with a source in the preview of a hovered leaf, then of a hovered cluster. */
  previewLeafVideos: number;
  previewClusterVideos: number;
  /** … and after the pointer left the chart. */
  videosAfterLeave: number;
}

/** Video elements that hold a source (a loaded or loading clip). */
const loadedVideos = () => [...document.querySelectorAll("video")].filter((v) => v.getAttribute("src") || v.src).length;

/**
 * The whole app on the fake server with an n-behaviour round: time to the chart on screen,
 * a click's and a hover's render (the app renders once per frame, so each is timed from the
 * start of the frame after the event to the end of its style/layout), and how many clips
 * are loaded along the way (posters only until a clip is hovered or in a group).
 */
async function runApp(n: number, updates = 30): Promise<AppBenchResult> {
  const synth = syntheticRound(n, { suggestions: 100, history: 400, seed: n });
  const host = document.getElementById("app")!;
  host.replaceChildren();
  localStorage.setItem(guideKey("groupwise"), "1");
  await afterPaint();
  let videosMax = 0;
  const watch = () => (videosMax = Math.max(videosMax, loadedVideos()));
  const t0 = performance.now();
  // Clips and posters as the server gives them: files by URL (benchmarks/web_render.py serves
  // one real clip and poster under clips/, and counts the requests), not the demo's inline SVG.
  const api = { ...fakeApi(synth, "groupwise"), clipUrl: (clip: string) => `clips/${clip}` };
  startApp(host, { api, search: "?session=s-demo" });
  const arcCount = () => host.querySelectorAll(".chart-svg .arc.leaf").length;
  while (arcCount() < n) await frame();
  const canvas = host.querySelector<HTMLCanvasElement>("canvas.chart-edges")!;
  while (!canvas.dataset.drawnAt) await frame();
  await afterPaint();
  const onScreenMs = performance.now() - t0;
  const videosAtLoad = host.querySelectorAll("video").length + document.querySelectorAll(".preview video").length;
  watch();

  /** Runs `act` and times the app's render in the next frame (it was scheduled by `act`). */
  const timed = (act: () => void) =>
    new Promise<number>((resolve) => {
      let start = 0;
      requestAnimationFrame(() => (start = performance.now()));
      act();
      requestAnimationFrame(() => {
        void document.body.offsetHeight;
        resolve(performance.now() - start);
      });
    });
  const svg = host.querySelector<SVGSVGElement>(".chart-svg")!;
  const arcEl = (id: string) => svg.querySelector<SVGPathElement>(`[data-id="${id}"]`)!;
  const rand = rng(11);
  const cands = synth.candidates;
  const selects: number[] = [];
  for (let i = 0; i < updates; i++) {
    const c = cands[Math.floor(rand() * cands.length)]!;
    const el = arcEl(c.id);
    selects.push(await timed(() => el.dispatchEvent(new MouseEvent("click", { bubbles: true, altKey: i % 2 === 1 }))));
    watch();
    await frame();
  }
  const hovers: number[] = [];
  for (let i = 0; i < updates; i++) {
    const el = arcEl(synth.leaves[Math.floor(rand() * n)]!);
    const r = el.getBoundingClientRect();
    const at = { bubbles: true, clientX: r.x + r.width / 2, clientY: r.y + r.height / 2 };
    hovers.push(await timed(() => el.dispatchEvent(new PointerEvent("pointerover", at))));
    watch();
    await frame();
  }
  const settle = () => new Promise((r) => setTimeout(r, 200));
  const hoverOn = async (id: string) => {
    const el = arcEl(id);
    const r = el.getBoundingClientRect();
    el.dispatchEvent(new PointerEvent("pointerover", { bubbles: true, clientX: r.x + r.width / 2, clientY: r.y + r.height / 2 }));
    await settle();
    watch();
    return [...document.querySelectorAll(".preview video")].filter((v) => v.getAttribute("src") || (v as HTMLVideoElement).src).length;
  };
  const previewLeafVideos = await hoverOn(synth.leaves[0]!);
  const previewClusterVideos = await hoverOn(cands[0]!.id);
  svg.dispatchEvent(new PointerEvent("pointerleave"));
  await settle();
  const videosAfterLeave = document.querySelectorAll(".preview video").length;
  return {
    leaves: n,
    onScreenMs,
    selectMedianMs: quantile(selects, 0.5),
    selectP95Ms: quantile(selects, 0.95),
    hoverMedianMs: quantile(hovers, 0.5),
    videosAtLoad,
    videosMax,
    previewLeafVideos,
    previewClusterVideos,
    videosAfterLeave,
  };
}

if (demo === "groupwise" || demo === "pairwise") {
  const n = Number(params.get("n") ?? 120);
  const synth = syntheticRound(n, { suggestions: 100, history: Number(params.get("history") ?? 24), seed: 3 });
  // ?phase=training|preparing|failed|finished shows the progress panel of that phase.
  const phase = params.get("phase") as SessionState["phase"] | null;
  const state: Partial<SessionState> = phase ? { phase } : {};
  if (phase === "failed") state.error = "training round 1 failed: CUDA out of memory (see the server log)";
  if (phase === "training") state.progress = { phase: "reward", fraction: 0.35, message: "reward model epoch 7 / 20" };
  const shared = params.get("shared");
  if (shared === "owner" || shared === "annotator") {
    const people = [
      { id: "owner", name: params.get("owner") ?? "Maria Garcia" },
      { id: "a-1", name: "Ann Lee" },
      { id: "a-2", name: "bob" },
    ];
    const me = shared === "owner" ? people[0]! : people[1]!;
    state.me = { ...me, owner: shared === "owner" };
    state.annotators = people.map((p, i) => ({
      ...p,
      comparisons: [14, 9, 3][i]!,
      pairs: [52, 31, 8][i]!,
      shown_s: [412, 388, 95][i]!,
      agreement: i === 2 ? { kappa: null, share: null, n: 0 } : { kappa: [0.62, 0.48][i]!, share: [0.8, 0.74][i]!, n: [10, 12][i]! },
      model_agreement: { share: [0.71, 0.66, 0.5][i]!, n: [40, 25, 8][i]! },
    }));
    synth.judgements.forEach((j, i) => (j.annotator = people[i % people.length]!));
  }
  const api = fakeApi(synth, demo, state);
  // ?training=continuous: the session trains continuously (the learning panel shows).
  if (params.get("training") === "continuous") {
    void api.session("s-demo").then((s) => {
      if (s !== STALE) s.settings.training = "continuous";
    });
  }
  // ?clips=served: clips and posters as files under clips/ (a test serves them and counts
  // the requests), instead of inline SVG posters.
  if (params.get("clips") === "served") api.clipUrl = (clip) => `clips/${clip}`;
  startApp(document.getElementById("app")!, { api, search: "?session=s-demo" });
} else {
  (window as unknown as { bench: { run: typeof run; app: typeof runApp } }).bench = { run, app: runApp };
  document.title = "groupwise bench (ready)";
}
