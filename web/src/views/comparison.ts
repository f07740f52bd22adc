/**
 * Comparison view (SPEC §9, right): the two groups side by side — A left, B right — as tinted,
 * labelled grids of looping muted clips started together; per clip remove / move to the
 * other group; the answer buttons; next suggestion, clear and undo.
 *
 * A clip's element is keyed by behaviour id and reused when it moves between groups, so its
 * video keeps playing; the clips restart together only when the set of behaviours changes.
 * A clip that leaves a group from its focused button hands the focus on (`lib/focus.ts`).
 */
import type { Label } from "../api";
import { question } from "../lib/format";
import { focusAfterLeaving } from "../lib/focus";
import { bestGrid } from "../lib/grid";
import { SPEEDS } from "../lib/page-settings";
import type { GroupId, Groups } from "../lib/selection";
import { MAX_GROUP, otherGroup } from "../lib/selection";
import type { Origin, State } from "../state";
import { clipVideo, loadClips, setRate, startTogether, unloadVideo } from "./clips";
import { attr, h, kbd, memo, text } from "./dom";

export interface ClipRef {
  src: string;
  poster?: string;
}

export interface ComparisonData {
  groups: Groups;
  target: GroupId;
  clipOf(id: string): ClipRef | null;
  /** Behaviours to highlight (the hovered leaf, or the leaves of the hovered cluster). */
  highlighted: ReadonlySet<string>;
  speed: number;
  /** What a clip shows and how fast it plays, e.g. "1.5 s · real speed". */
  clipCaption: string;
  /** Answers are possible (both groups filled, round open, nothing in flight). */
  canAnswer: boolean;
  /** Why answering is not possible, when it is not. */
  answerHint: string;
  submitting: boolean;
  origin: Origin;
  suggestionStatus: State["suggestionStatus"];
  canSuggest: boolean;
  canUndo: boolean;
  undoing: boolean;
}

export interface ComparisonHandlers {
  remove(id: string): void;
  move(id: string): void;
  hover(id: string | null): void;
  answer(label: Label): void;
  next(): void;
  clear(): void;
  undo(): void;
  speed(rate: number): void;
  target(group: GroupId): void;
  restart(): void;
}

interface ClipItem {
  li: HTMLLIElement;
  video: HTMLVideoElement;
  move: HTMLButtonElement;
  remove: HTMLButtonElement;
  group: GroupId | null;
}

interface GroupPanel {
  root: HTMLElement;
  list: HTMLUListElement;
  count: HTMLElement;
  fill: HTMLButtonElement;
  empty: HTMLElement;
}

/** A clip leaving its group from its own focused button (move or remove). */
interface Leaving {
  id: string;
  tool: "move" | "remove";
  group: GroupId;
  index: number;
  button: HTMLButtonElement;
}

interface View {
  panels: Record<GroupId, GroupPanel>;
  items: Map<string, ClipItem>;
  origin: HTMLElement;
  speed: HTMLSelectElement;
  timing: HTMLElement;
  answers: Record<Label, HTMLButtonElement>;
  hint: HTMLElement;
  next: HTMLButtonElement;
  clear: HTMLButtonElement;
  undo: HTMLButtonElement;
  handlers: ComparisonHandlers | null;
  data: ComparisonData | null;
  members: string;
  leaving: Leaving | null;
}

const views = new WeakMap<Element, View>();

export function renderComparison(
  element: HTMLElement,
  data: ComparisonData,
  handlers: ComparisonHandlers,
): void {
  const view = memo(views, element, () => build(element));
  view.handlers = handlers;
  const prev = view.data;
  view.data = data;

  if (prev?.groups !== data.groups || prev?.clipOf !== data.clipOf) {
    placeClips(view, data);
    if (prev?.groups !== data.groups) handFocusOn(view, data);
  }
  for (const g of ["A", "B"] as const) {
    const p = view.panels[g];
    const n = data.groups[g].length;
    text(p.count, `${n} / ${MAX_GROUP}`);
    p.root.classList.toggle("is-target", data.target === g);
    attr(p.fill, "aria-pressed", String(data.target === g));
    text(p.fill, data.target === g ? `Clicks fill ${g}` : `Fill ${g}`);
    attr(p.fill, "aria-label", data.target === g ? `Clicks fill group ${g}` : `Let clicks fill group ${g}`);
    p.empty.hidden = n > 0;
  }
  for (const [id, item] of view.items) item.li.classList.toggle("linked", data.highlighted.has(id));
  if (prev?.speed !== data.speed) {
    view.speed.value = String(data.speed);
    setRate(
      [...view.items.values()].map((i) => i.video),
      data.speed,
    );
  }
  for (const b of Object.values(view.answers)) b.disabled = !data.canAnswer;
  view.answers.left.parentElement!.classList.toggle("busy", data.submitting);
  text(view.hint, data.canAnswer ? "" : data.answerHint);
  view.next.disabled = !data.canSuggest || data.suggestionStatus === "loading";
  view.clear.disabled = data.groups.A.length + data.groups.B.length === 0;
  view.undo.disabled = !data.canUndo || data.undoing;
  text(view.origin, originText(data));
  text(view.timing, data.clipCaption);
}

function originText(d: ComparisonData): string {
  if (d.suggestionStatus === "loading") return "Finding a suggestion…";
  const empty = d.groups.A.length + d.groups.B.length === 0;
  if (empty && d.suggestionStatus === "none") {
    return "No suggestions left: choose groups in the chart.";
  }
  if (empty) return "Choose groups in the chart, or ask for a suggestion.";
  const edits = d.origin.edits === 1 ? "1 edit" : `${d.origin.edits} edits`;
  return d.origin.source === "suggested" ? `Suggested comparison · ${edits}` : `Your selection · ${edits}`;
}

function build(element: HTMLElement): View {
  const panel = (g: GroupId): GroupPanel => {
    const side = g === "A" ? "left" : "right";
    const count = h("span", { class: "group-count" });
    const fill = h("button", { type: "button", class: "fill-target", "aria-pressed": "false" });
    const list = h("ul", { class: "clip-grid", "aria-label": `Clips of group ${g}` });
    const empty = h(
      "p",
      { class: "group-empty" },
      `Empty. Click a cluster or a behaviour in the chart to fill group ${g}.`,
    );
    const root = h(
      "section",
      { class: `group group-${g}`, "aria-label": `Group ${g} (${side})` },
      h(
        "header",
        { class: "group-head" },
        h("span", { class: "group-badge", "aria-hidden": "true" }, g),
        h("span", { class: "group-name" }, `Group ${g}`, h("span", { class: "group-side" }, ` · ${side}`)),
        count,
        fill,
      ),
      h("div", { class: "clip-area" }, list, empty),
    );
    fill.addEventListener("click", () => view.handlers?.target(g));
    return { root, list, count, fill, empty };
  };

  const origin = h("span", { class: "panel-sub origin", role: "status" });
  const speed = h("select", { "aria-label": "Playback speed" });
  for (const s of SPEEDS) speed.append(h("option", { value: s }, `${s}×`));
  const timing = h("span", { class: "clip-timing", title: "Simulated time each clip shows, and how fast it plays" });
  const restart = h(
    "button",
    { type: "button", class: "ghost", title: "Start all clips together again", "aria-label": "Restart all clips together" },
    "↻ Restart",
  );
  const head = h(
    "header",
    { class: "panel-head" },
    h("h2", { id: "comparison-title" }, question("group")),
    origin,
    h("div", { class: "head-tools" }, timing, h("label", { class: "speed" }, "Speed ", speed), restart),
  );

  const answer = (label: Label, content: Array<Node | string>, shortcut: string, name: string) => {
    const b = h("button", {
      type: "button",
      class: `answer answer-${label}`,
      "aria-keyshortcuts": shortcut,
      "aria-label": name,
    });
    b.append(...content);
    b.addEventListener("click", () => view.handlers?.answer(label));
    return b;
  };
  const answers: Record<Label, HTMLButtonElement> = {
    left: answer("left", [h("span", { class: "arrow" }, "←"), " A is better", kbd("←", "A")], "ArrowLeft A", "Group A (left) is better"),
    equal: answer("equal", [h("span", { class: "arrow" }, "↑"), " About equal", kbd("↑", "W")], "ArrowUp W", "Both groups are about equal"),
    right: answer("right", ["B is better ", h("span", { class: "arrow" }, "→"), kbd("→", "D")], "ArrowRight D", "Group B (right) is better"),
  };
  const hint = h("p", { class: "answer-hint", role: "status" });
  const next = h("button", { type: "button" }, "Next suggestion", kbd("N"));
  const clear = h("button", { type: "button", class: "ghost" }, "Clear groups");
  const undo = h("button", { type: "button", class: "ghost" }, "Undo last answer", kbd("U"));

  const panels = { A: panel("A"), B: panel("B") };
  element.classList.add("panel", "comparison");
  element.setAttribute("aria-labelledby", "comparison-title");
  element.replaceChildren(
    head,
    h("div", { class: "groups" }, panels.A.root, panels.B.root),
    h("div", { class: "answer-bar", role: "group", "aria-label": "Your answer" }, answers.left, answers.equal, answers.right),
    h("div", { class: "actions" }, hint, h("div", { class: "action-buttons" }, next, clear, undo)),
  );

  const view: View = {
    panels,
    items: new Map(),
    origin,
    speed,
    timing,
    answers,
    hint,
    next,
    clear,
    undo,
    handlers: null,
    data: null,
    members: "",
    leaving: null,
  };
  speed.addEventListener("change", () => view.handlers?.speed(Number(speed.value)));
  restart.addEventListener("click", () => view.handlers?.restart());
  next.addEventListener("click", () => view.handlers?.next());
  clear.addEventListener("click", () => view.handlers?.clear());
  undo.addEventListener("click", () => view.handlers?.undo());
  for (const g of ["A", "B"] as const) {
    const ro = new ResizeObserver(() => fitGrid(panels[g]));
    ro.observe(panels[g].list.parentElement!);
  }
  return view;
}

function clipItem(view: View, id: string, ref: ClipRef | null): ClipItem {
  const video = clipVideo(ref?.src ?? "", ref?.poster, `clip of behaviour ${id}`);
  const move = h("button", { type: "button", class: "clip-tool move" });
  const remove = h("button", { type: "button", class: "clip-tool remove" }, "×");
  const li = h(
    "li",
    { class: "clip", "data-id": id },
    video,
    h("span", { class: "clip-caption" }, id),
    h("div", { class: "clip-tools" }, move, remove),
  );
  const item: ClipItem = { li, video, move, remove, group: null };
  const leave = (tool: Leaving["tool"], button: HTMLButtonElement) => {
    const group = item.group;
    view.leaving =
      group && document.activeElement === button
        ? { id, tool, group, index: [...view.panels[group].list.children].indexOf(li), button }
        : null;
  };
  move.addEventListener("click", () => {
    leave("move", move);
    view.handlers?.move(id);
  });
  remove.addEventListener("click", () => {
    leave("remove", remove);
    view.handlers?.remove(id);
  });
  li.addEventListener("pointerenter", () => view.handlers?.hover(id));
  li.addEventListener("pointerleave", () => view.handlers?.hover(null));
  li.addEventListener("focusin", () => view.handlers?.hover(id));
  li.addEventListener("focusout", (e) => {
    if (!li.contains(e.relatedTarget as Node | null)) view.handlers?.hover(null);
  });
  return item;
}

function placeClips(view: View, data: ComparisonData): void {
  const wanted = new Set([...data.groups.A, ...data.groups.B]);
  for (const [id, item] of view.items) {
    if (!wanted.has(id)) {
      unloadVideo(item.video);
      item.li.remove();
      view.items.delete(id);
    }
  }
  const fresh: HTMLVideoElement[] = [];
  for (const g of ["A", "B"] as const) {
    const list = view.panels[g].list;
    const other = otherGroup(g);
    data.groups[g].forEach((id, i) => {
      let item = view.items.get(id);
      if (!item) {
        item = clipItem(view, id, data.clipOf(id));
        view.items.set(id, item);
        fresh.push(item.video);
      }
      if (item.group !== g) {
        item.group = g;
        item.move.textContent = g === "A" ? "→ B" : "A ←";
        item.move.setAttribute("aria-label", `Move ${id} to group ${other}`);
        item.move.title = `Move to group ${other}`;
        item.remove.setAttribute("aria-label", `Remove ${id} from group ${g}`);
        item.remove.title = `Remove from group ${g}`;
      }
      if (list.children[i] !== item.li) list.insertBefore(item.li, list.children[i] ?? null);
    });
    fitGrid(view.panels[g]);
  }
  loadClips(fresh); // in the groups' order, ahead of clips asked for before
  const members = [...wanted].sort().join(" ");
  if (members !== view.members) {
    view.members = members;
    void startTogether(
      [...view.items.values()].map((i) => i.video),
      data.speed,
    );
  }
}

/**
 * After a clip left its group from its focused button, the focus stays on the same button of
 * the clip now in its place (or the one before it), so Enter can go on; from an emptied
 * group it follows a moved clip, or goes to the group's "Fill" button after a removal
 * (issue 23: it fell to the page's body).
 */
function handFocusOn(view: View, data: ComparisonData): void {
  const leaving = view.leaving;
  view.leaving = null;
  if (!leaving || data.groups[leaving.group].includes(leaving.id)) return;
  const active = document.activeElement;
  if (active && active !== document.body && active !== leaving.button) return; // the person moved on
  const group = data.groups[leaving.group];
  const i = focusAfterLeaving(leaving.index, group.length);
  const stay = i === null ? undefined : view.items.get(group[i]!);
  const next = stay
    ? stay[leaving.tool]
    : leaving.tool === "move"
      ? view.items.get(leaving.id)?.move
      : view.panels[leaving.group].fill;
  next?.focus();
}

function fitGrid(panel: GroupPanel): void {
  const list = panel.list;
  const n = list.children.length;
  if (n === 0) return;
  const { cols, cell } = bestGrid(n, list.clientWidth, list.clientHeight);
  list.style.setProperty("--cols", String(cols));
  list.style.setProperty("--cell", `${Math.max(40, Math.min(cell, 360))}px`);
}
