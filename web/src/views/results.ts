/**
 * The finished session: the final agent's video, its evaluation (a target env's episode
 * score in the target's unit, with its threshold, and the per-step sum beside it; else the
 * true return) and that score per round as a small chart, the downloads (the agent as one
 * zip, the judgements), the choice of the agent to take away among the rounds' agents
 * (`views/takeaway.ts`), and "Continue training" (more PPO steps on the frozen reward
 * model, or more rounds).
 */
import type { AgentOut, ContinueIn, SessionState, TrainingPoint } from "../api";
import { plural } from "../lib/format";
import {
  type ChartGeometry,
  capitalise,
  chartGeometry,
  chartSeries,
  formatValue,
  scoreLines,
  scoreText,
} from "../lib/results";
import { choiceText } from "../lib/takeaway";
import { h, memo, s, text } from "./dom";
import { renderTakeaway } from "./takeaway";
import { drawCurve } from "./training";

export interface ResultsData {
  session: SessionState;
  agent: AgentOut;
  videoUrl: string;
  downloadUrl: string;
  exportUrl: string;
  /** Round `round`'s clip (`GET …/agent/rounds/{round}.mp4`). */
  roundVideoUrl(round: number): string;
  busy: boolean;
  /** Whether this page is the session's owner: only they continue training (issue 21). */
  owner?: boolean;
  /** The session's learning curve (`lib/training.ts`), drawn under the rounds' chart. */
  training: readonly TrainingPoint[];
}

export interface ResultsHandlers {
  continueTraining(body: ContinueIn): void;
  /** Round `round`'s agent becomes the download: resolves to the new agent, or rejects with
   * an error whose message says why not. */
  pickAgent(round: number): Promise<AgentOut>;
}

interface View {
  panelSub: HTMLElement;
  title: HTMLElement;
  summary: HTMLElement;
  score: HTMLElement;
  scoreLabel: HTMLElement;
  scoreValue: HTMLElement;
  scoreGoal: HTMLElement;
  scoreDetail: HTMLElement;
  video: HTMLVideoElement;
  caption: HTMLElement;
  chartTitle: HTMLElement;
  chart: SVGSVGElement;
  chartNote: HTMLElement;
  learning: HTMLElement;
  learningChart: SVGSVGElement;
  /** The points the learning chart shows (redrawn when they change). */
  learned: readonly TrainingPoint[] | null;
  takeaway: HTMLElement;
  /** A pick on its way to the server, or why the last one failed. */
  pick: { pending: number | null; error: string | null };
  /** What the choice was last drawn from (redrawn when a pick settles). */
  last: ResultsData | null;
  download: HTMLAnchorElement;
  hint: HTMLElement;
  exportLink: HTMLAnchorElement;
  kind: HTMLSelectElement;
  amount: HTMLInputElement;
  submit: HTMLButtonElement;
  /** The agent the view shows ("sid:session round:agent round"): another one resets the
   * video and the chart; another session round (it trained again) resets the forms too. */
  shown: string;
  handlers: ResultsHandlers | null;
}

const views = new WeakMap<Element, View>();
const CHART = { width: 460, height: 190 };
const LEARNING_CHART = { width: 460, height: 130 };

export function renderResults(element: HTMLElement, data: ResultsData, handlers: ResultsHandlers): void {
  const view = memo(views, element, () => build(element));
  view.handlers = handlers;
  const { session: st, agent } = data;
  const key = `${st.id}:${st.round}:${agent.round}`;
  if (view.shown !== key) {
    const sameSession = view.shown.startsWith(`${st.id}:${st.round}:`);
    view.shown = key;
    view.video.src = data.videoUrl;
    view.download.href = data.downloadUrl;
    view.download.setAttribute("download", `groupwise-agent-${st.id}-round-${agent.round}.zip`);
    if (!sameSession) {
      // a new agent, not another round's of the same session: the forms start over
      view.kind.value = "steps";
      view.amount.value = String(defaultSteps(st));
      view.amount.dataset.steps = view.amount.value;
      view.pick = { pending: null, error: null };
    }
    drawChart(view.chart, agent);
  }
  view.last = data;
  drawTakeaway(view, agent);
  view.exportLink.href = data.exportUrl;
  view.learning.hidden = !data.training.some((p) => p.true_return !== null);
  // a target env's return is the sum of its per-step scores (agent.measure says so)
  text(view.learning.querySelector(".learning-title")!, `${capitalise(agent.measure)} over the session`);
  if (!view.learning.hidden && view.learned !== data.training) {
    view.learned = data.training;
    drawCurve(view.learningChart, data.training, LEARNING_CHART, agent.target ?? null);
  }
  const c = st.counts;
  const frozen = agent.rounds.filter((r) => !r.feedback);
  const feedback = agent.rounds.filter((r) => r.feedback);
  text(view.panelSub, choiceText(agent).replace("Chosen: r", "R"));
  text(view.title, "Session finished: your agent");
  text(
    view.summary,
    `${plural(c.comparisons_total, "comparison")} and ${plural(c.pairs_total, "preference pair")} ` +
      `over ${plural(feedback.length, "round")} of feedback, then ` +
      `${frozen.length ? plural(frozen.length, "round") : "no round"} of PPO on the frozen reward model: ` +
      `${(agent.rounds.at(-1)?.env_steps ?? agent.env_steps).toLocaleString("en")} PPO steps in all.`,
  );
  const v = agent.video;
  const t = agent.target;
  text(
    view.caption,
    [
      `Round ${agent.round} · one greedy episode`,
      v ? `${formatValue(v.seconds)} s at real speed` : null,
      v && t && v.target_score !== null ? `${t.unit} ${formatValue(v.target_score)}` : null,
      v && t ? `per-step sum ${formatValue(v.episode_return)} ${t.step_unit}` : null,
      v && !t ? `${agent.measure} ${formatValue(v.episode_return)}` : null,
    ]
      .filter(Boolean)
      .join(" · "),
  );
  const lines = scoreLines(agent);
  const episodes = st.settings.eval_episodes;
  view.score.hidden = lines === null;
  view.score.setAttribute("aria-label", `Evaluation: ${scoreText(agent)}`);
  text(view.scoreLabel, lines?.label ?? "");
  text(view.scoreValue, lines?.value ?? "");
  text(view.scoreGoal, lines?.goal ? `(${lines.goal})` : "");
  text(
    view.scoreDetail,
    [
      lines?.detail ? capitalise(lines.detail) : null,
      `the greedy policy over ${plural(episodes, "evaluation episode")} after round ${agent.round}`,
    ]
      .filter(Boolean)
      .join(" · "),
  );
  const series = chartSeries(agent);
  text(view.chartTitle, `${capitalise(series.name)}, per round`);
  text(
    view.chartNote,
    series.rounds.some((r) => r.value === null)
      ? "Rounds without a point were not evaluated (eval_episodes = 0)."
      : "Filled: after a round of feedback; hollow: PPO on the frozen reward model only; " +
          "ringed: the agent you take." +
          (series.reference === null ? "" : " Dashed: the threshold of success."),
  );
  view.submit.disabled = data.busy;
  view.hint.replaceChildren(
    `The download is round ${agent.round}'s agent. Load it in Python with `,
    h("code", {}, "groupwise.load_agent(path)"),
    "; its README says how.",
  );
  const form = view.submit.closest("form");
  if (form) form.hidden = data.owner === false;
}

function drawTakeaway(view: View, agent: AgentOut): void {
  const data = view.last;
  if (!data) return;
  renderTakeaway(
    view.takeaway,
    {
      agent,
      clipUrl: data.roundVideoUrl,
      pending: view.pick.pending,
      busy: data.busy,
      owner: data.owner !== false,
      error: view.pick.error,
    },
    { pick: (round) => pick(view, agent, round) },
  );
}

/** Sends a pick (one at a time); draws the choice when it settles, or the reason it failed. */
function pick(view: View, agent: AgentOut, round: number): void {
  const handlers = view.handlers;
  if (!handlers || view.pick.pending !== null) return;
  view.pick = { pending: round, error: null };
  drawTakeaway(view, agent);
  handlers.pickAgent(round).then(
    (picked) => {
      view.pick = { pending: null, error: null };
      drawTakeaway(view, picked);
    },
    (err: unknown) => {
      const why = err instanceof Error ? err.message : String(err);
      view.pick = { pending: null, error: `Round ${round}'s agent was not taken: ${why}` };
      drawTakeaway(view, view.last?.agent ?? agent);
    },
  );
}

/** The steps "Continue training" offers first: as many as the session's final phase. */
function defaultSteps(session: SessionState): number {
  const settings = session.settings;
  return Math.max(1, settings.final_steps ?? 2 * settings.ppo_steps_per_round);
}

function drawChart(svg: SVGSVGElement, agent: AgentOut): void {
  const series = chartSeries(agent);
  const g: ChartGeometry = chartGeometry(series.rounds, CHART.width, CHART.height, undefined, series.reference);
  const a = g.area;
  const children: SVGElement[] = [];
  for (const t of g.yTicks) {
    children.push(s("line", { class: "grid", x1: a.left, x2: a.right, y1: t.y, y2: t.y }));
    children.push(s("text", { class: "tick y", x: a.left - 6, y: t.y, dy: "0.32em" }, t.label));
  }
  if (g.reference) {
    const y = g.reference.y;
    children.push(s("line", { class: "threshold", x1: a.left, x2: a.right, y1: y, y2: y }));
    children.push(
      s("text", { class: "threshold-label", x: a.right - 4, y: y - 4 }, `threshold ${formatValue(g.reference.value)}`),
    );
  }
  for (const t of g.xTicks) {
    children.push(s("text", { class: "tick x", x: t.x, y: a.bottom + 16 }, String(t.round)));
  }
  children.push(s("line", { class: "axis", x1: a.left, x2: a.right, y1: a.bottom, y2: a.bottom }));
  if (g.path) children.push(s("path", { class: "line", d: g.path }));
  for (const p of g.points) {
    if (p.y === null) continue;
    if (p.round === agent.round) {
      children.push(s("circle", { class: "chosen-ring", cx: p.x, cy: p.y, r: 8.5, "aria-hidden": "true" }));
    }
    const label =
      `round ${p.round}${p.feedback ? "" : " (PPO only)"}: ${series.name} ` + `${formatValue(p.value ?? 0)}`;
    children.push(
      s(
        "circle",
        { class: p.feedback ? "point" : "point frozen", cx: p.x, cy: p.y, r: 4.5, "data-round": p.round },
        s("title", {}, label),
      ),
    );
  }
  children.push(s("text", { class: "axis-label", x: (a.left + a.right) / 2, y: CHART.height - 1 }, "round"));
  svg.replaceChildren(...children);
  svg.setAttribute(
    "aria-label",
    `${series.name} per round: ` +
      series.rounds
        .map((r) => `round ${r.round} ${r.value === null ? "not evaluated" : formatValue(r.value)}`)
        .join(", ") +
      (series.reference === null ? "" : `; threshold ${formatValue(series.reference)}`),
  );
}

function build(element: HTMLElement): View {
  const title = h("h2", { class: "results-title" });
  const summary = h("p", { class: "results-summary" });
  const scoreLabel = h("span", { class: "score-label" });
  const scoreValue = h("strong", { class: "score-value num" });
  const scoreGoal = h("span", { class: "score-goal num" });
  const scoreDetail = h("p", { class: "score-detail muted num" });
  const score = h(
    "section",
    { class: "results-score" },
    h("p", { class: "score-main" }, scoreLabel, " ", scoreValue, " ", scoreGoal),
    scoreDetail,
  );
  const video = h("video", {
    class: "agent-video",
    controls: true,
    autoplay: true,
    muted: true,
    loop: true,
    playsinline: true,
    preload: "auto",
    "aria-label": "The agent you take: one greedy episode",
  });
  video.muted = true; // the attribute alone does not allow autoplay everywhere
  const caption = h("figcaption", { class: "agent-caption num" });
  const chartTitle = h("h3", { class: "chart-title" });
  const chart = s("svg", {
    class: "return-chart",
    viewBox: `0 0 ${CHART.width} ${CHART.height}`,
    role: "img",
  });
  const chartNote = h("p", { class: "chart-note muted" });
  const learningChart = s("svg", { class: "return-chart", role: "img" });
  const learning = h(
    "section",
    { class: "results-chart results-learning", hidden: true },
    h("h3", { class: "chart-title learning-title" }, "True return over the session"),
    learningChart,
    h("p", { class: "chart-note muted" }, "The greedy policy, measured while it trained (minutes:seconds since the first point)."),
  );
  const download = h(
    "a",
    { class: "button primary", download: "", "aria-describedby": "results-hint" },
    "Download agent (.zip)",
  );
  const exportLink = h("a", { class: "button", download: "" }, "Download judgements (JSONL)");
  const kind = h(
    "select",
    { "aria-label": "What to train more" },
    h("option", { value: "steps" }, "PPO steps (frozen reward)"),
    h("option", { value: "rounds" }, "rounds of feedback"),
  );
  const amount = h("input", {
    type: "number",
    min: 1,
    step: 1,
    class: "num",
    "aria-label": "How many more",
  });
  const submit = h("button", { type: "submit", class: "primary" }, "Continue training");
  const form = h(
    "form",
    { class: "continue-form", "aria-labelledby": "continue-title" },
    h("h3", { class: "continue-title", id: "continue-title" }, "Continue training"),
    h(
      "p",
      { class: "continue-note muted" },
      "More PPO steps on the frozen reward model, or more rounds of your feedback (the final " +
        "training follows them). The video, chart and download then show the new agent.",
    ),
    h("div", { class: "continue-row" }, amount, kind, submit),
  );
  const panelSub = h("span", { class: "panel-sub" });
  const takeaway = h("section", { class: "results-takeaway" });
  const hint = h("p", { class: "results-hint muted", id: "results-hint" });
  element.classList.add("results");
  element.replaceChildren(
    h(
      "div",
      { class: "panel results-video" },
      h("div", { class: "panel-head" }, h("h2", { class: "panel-title" }, "Your agent"), panelSub),
      h("figure", { class: "agent-figure" }, video, caption),
    ),
    h(
      "div",
      { class: "panel results-side" },
      h(
        "div",
        { class: "results-body" },
        title,
        summary,
        score,
        h("section", { class: "results-chart" }, chartTitle, chart, chartNote),
        takeaway,
        learning,
        h("div", { class: "results-actions" }, download, exportLink),
        hint,
        form,
      ),
    ),
  );
  const view: View = {
    panelSub,
    title,
    summary,
    score,
    scoreLabel,
    scoreValue,
    scoreGoal,
    scoreDetail,
    video,
    caption,
    chartTitle,
    chart,
    chartNote,
    learning,
    learningChart,
    learned: null,
    takeaway,
    pick: { pending: null, error: null },
    last: null,
    download,
    hint,
    exportLink,
    kind,
    amount,
    submit,
    shown: "",
    handlers: null,
  };
  kind.addEventListener("change", () => {
    amount.value = kind.value === "rounds" ? "1" : amount.dataset.steps ?? amount.value;
  });
  amount.addEventListener("input", () => {
    if (kind.value === "steps") amount.dataset.steps = amount.value;
  });
  form.addEventListener("submit", (e) => {
    e.preventDefault();
    const n = Math.floor(Number(amount.value));
    if (!Number.isFinite(n) || n < 1) {
      amount.setCustomValidity("Enter a whole number of at least 1.");
      amount.reportValidity();
      return;
    }
    amount.setCustomValidity("");
    view.handlers?.continueTraining(kind.value === "rounds" ? { rounds: n } : { steps: n });
  });
  return view;
}
