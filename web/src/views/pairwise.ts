/**
 * The pairwise baseline (SPEC §9): the standard RLHF interface of two clips with left / right
 * / equal / skip. The following pair's videos load in a hidden slot and are moved into
 * place when the current pair is answered, so the next pair shows at once.
 */
import type { Label, PairQuery } from "../api";
import { question } from "../lib/format";
import { SPEEDS } from "../lib/page-settings";
import { loadClips, posterClip, startTogether, unloadVideo, type PosterClip } from "./clips";
import { h, kbd, memo, text } from "./dom";

export interface PairwiseData {
  current: PairQuery | null;
  following: PairQuery | null;
  clipUrl(clip: string): string;
  canAnswer: boolean;
  hint: string;
  submitting: boolean;
  loading: boolean;
  exhausted: boolean;
  canUndo: boolean;
  speed: number;
  /** What a clip shows and how fast it plays, e.g. "1.5 s · real speed". */
  clipCaption: string;
}

export interface PairwiseHandlers {
  answer(label: Label): void;
  skip(): void;
  undo(): void;
  speed(rate: number): void;
}

interface View {
  pair: HTMLElement;
  left: HTMLElement;
  right: HTMLElement;
  leftCaption: HTMLElement;
  rightCaption: HTMLElement;
  prefetch: HTMLElement;
  empty: HTMLElement;
  buttons: Record<Label | "skip", HTMLButtonElement>;
  undo: HTMLButtonElement;
  hint: HTMLElement;
  speed: HTMLSelectElement;
  timing: HTMLElement;
  /** Loaded clips by source URL: visible, prefetching, or about to be dropped. */
  videos: Map<string, PosterClip>;
  shownKey: string;
  handlers: PairwiseHandlers | null;
}

const views = new WeakMap<Element, View>();

export function renderPairwise(element: HTMLElement, data: PairwiseData, handlers: PairwiseHandlers): void {
  const view = memo(views, element, () => build(element));
  view.handlers = handlers;
  const cur = data.current;
  const key = cur ? `${cur.left}:${cur.right}` : "";
  const srcs = {
    left: cur ? data.clipUrl(cur.left_clip) : null,
    right: cur ? data.clipUrl(cur.right_clip) : null,
    next: data.following
      ? [data.clipUrl(data.following.left_clip), data.clipUrl(data.following.right_clip)]
      : [],
  };
  const posters = new Map<string, string>();
  for (const p of [cur, data.following]) {
    if (!p) continue;
    posters.set(data.clipUrl(p.left_clip), data.clipUrl(p.left_poster));
    posters.set(data.clipUrl(p.right_clip), data.clipUrl(p.right_poster));
  }
  const take = (src: string, label: string) => {
    let clip = view.videos.get(src);
    if (!clip) {
      clip = posterClip(src, posters.get(src) ?? "", label);
      view.videos.set(src, clip);
    }
    clip.video.setAttribute("aria-label", label);
    return clip;
  };
  const keep = new Set<string>();
  if (key !== view.shownKey) {
    view.shownKey = key;
    view.pair.dataset.pair = key;
    const shown: HTMLVideoElement[] = [];
    if (cur && srcs.left && srcs.right) {
      const l = take(srcs.left, `left clip, behaviour ${cur.left}`);
      const r = take(srcs.right, `right clip, behaviour ${cur.right}`);
      view.left.replaceChildren(l.frame);
      view.right.replaceChildren(r.frame);
      shown.push(l.video, r.video);
      loadClips(shown); // ahead of any prefetch still waiting
    } else {
      view.left.replaceChildren();
      view.right.replaceChildren();
    }
    void startTogether(shown, data.speed);
  }
  if (srcs.left) keep.add(srcs.left);
  if (srcs.right) keep.add(srcs.right);
  const pre: PosterClip[] = [];
  for (const src of srcs.next) {
    keep.add(src);
    if (src !== srcs.left && src !== srcs.right) pre.push(take(src, "next clip (loading)"));
  }
  view.prefetch.replaceChildren(...pre.map((clip) => clip.frame));
  loadClips(
    pre.map((clip) => clip.video),
    "last",
  );
  for (const [src, clip] of view.videos) {
    if (!keep.has(src)) {
      unloadVideo(clip.video);
      clip.frame.remove();
      view.videos.delete(src);
    }
  }
  for (const { video } of view.videos.values()) if (video.playbackRate !== data.speed) video.playbackRate = data.speed;
  view.speed.value = String(data.speed);
  text(view.timing, data.clipCaption);
  text(view.leftCaption, cur ? `Left · ${cur.left}` : "Left");
  text(view.rightCaption, cur ? `Right · ${cur.right}` : "Right");
  view.empty.hidden = cur !== null;
  text(
    view.empty,
    data.exhausted ? "No pairs left in this round. End the round to train on your answers." : "Loading the next pair…",
  );
  for (const b of Object.values(view.buttons)) b.disabled = !data.canAnswer || !cur;
  view.undo.disabled = !data.canUndo;
  text(view.hint, data.canAnswer ? "" : data.hint);
}

function build(element: HTMLElement): View {
  const left = h("div", { class: "pair-video" });
  const right = h("div", { class: "pair-video" });
  const leftCaption = h("figcaption", {});
  const rightCaption = h("figcaption", {});
  const prefetch = h("div", { class: "prefetch", "aria-hidden": "true" });
  const empty = h("p", { class: "pair-empty", role: "status" });
  const pair = h(
    "div",
    { class: "pair" },
    h("figure", { class: "pair-clip pair-left" }, left, leftCaption),
    h("figure", { class: "pair-clip pair-right" }, right, rightCaption),
    empty,
  );
  const button = (label: Label | "skip", content: Array<Node | string>, keys: string, name: string) => {
    const b = h("button", { type: "button", class: `answer answer-${label}`, "aria-keyshortcuts": keys, "aria-label": name });
    b.append(...content);
    return b;
  };
  const buttons = {
    left: button("left", [h("span", { class: "arrow" }, "←"), " Left is better", kbd("←", "A")], "ArrowLeft A", "Left clip is better"),
    equal: button("equal", [h("span", { class: "arrow" }, "↑"), " About equal", kbd("↑", "W")], "ArrowUp W", "Both clips are about equal"),
    skip: button("skip", [h("span", { class: "arrow" }, "↓"), " Skip", kbd("↓", "S")], "ArrowDown S", "Skip this pair"),
    right: button("right", ["Right is better ", h("span", { class: "arrow" }, "→"), kbd("→", "D")], "ArrowRight D", "Right clip is better"),
  };
  const undo = h("button", { type: "button", class: "ghost" }, "Undo last answer", kbd("U"));
  const hint = h("p", { class: "answer-hint", role: "status" });
  const speed = h("select", { "aria-label": "Playback speed" });
  for (const s of SPEEDS) speed.append(h("option", { value: s }, `${s}×`));
  const timing = h("span", { class: "clip-timing", title: "Simulated time each clip shows, and how fast it plays" });
  element.classList.add("panel", "pairwise");
  element.setAttribute("aria-labelledby", "pairwise-title");
  element.replaceChildren(
    h(
      "header",
      { class: "panel-head" },
      h("h2", { id: "pairwise-title" }, question("clip")),
      h("div", { class: "head-tools" }, timing, h("label", { class: "speed" }, "Speed ", speed)),
    ),
    pair,
    h(
      "div",
      { class: "answer-bar four", role: "group", "aria-label": "Your answer" },
      buttons.left,
      buttons.equal,
      buttons.skip,
      buttons.right,
    ),
    h("div", { class: "actions" }, hint, h("div", { class: "action-buttons" }, undo)),
    prefetch,
  );
  const view: View = {
    pair,
    left,
    right,
    leftCaption,
    rightCaption,
    prefetch,
    empty,
    buttons,
    undo,
    hint,
    speed,
    timing,
    videos: new Map(),
    shownKey: "\u0000",
    handlers: null,
  };
  buttons.left.addEventListener("click", () => view.handlers?.answer("left"));
  buttons.right.addEventListener("click", () => view.handlers?.answer("right"));
  buttons.equal.addEventListener("click", () => view.handlers?.answer("equal"));
  buttons.skip.addEventListener("click", () => view.handlers?.skip());
  undo.addEventListener("click", () => view.handlers?.undo());
  speed.addEventListener("change", () => view.handlers?.speed(Number(speed.value)));
  return view;
}
