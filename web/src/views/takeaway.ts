/**
 * The results page's choice of the take-away agent (issue 20): each round's agent with its
 * clip, round and score, the current choice marked, and "Take this agent" per round. Clips
 * load their first frame only and play one at a time: while the pointer rests on one, or
 * from its play button (click, Enter or Space) until it is pressed again.
 */
import type { AgentOut } from "../api";
import { type TakeawayRound, choiceText, takeawayRounds } from "../lib/takeaway";
import { attr, h, memo, text } from "./dom";

export interface TakeawayData {
  agent: AgentOut;
  /** Round `round`'s clip. */
  clipUrl(round: number): string;
  /** The round whose pick is on its way to the server; null when none is. */
  pending: number | null;
  /** The session is being changed (training continues): no pick meanwhile. */
  busy: boolean;
  /** Only the session's owner picks (the server answers others 403): the others see the
   * choice and the clips without the buttons. */
  owner: boolean;
  /** Why the last pick failed (the server's reason); null when it did not. */
  error: string | null;
}

export interface TakeawayHandlers {
  pick(round: number): void;
}

interface Card {
  item: HTMLLIElement;
  video: HTMLVideoElement | null;
  play: HTMLButtonElement | null;
  score: HTMLElement;
  mark: HTMLElement;
  take: HTMLButtonElement;
  blocked: HTMLElement;
  /** Played from its button: it plays on after the pointer leaves. */
  pinned: boolean;
}

interface View {
  note: HTMLElement;
  choice: HTMLElement;
  error: HTMLElement;
  list: HTMLUListElement;
  cards: Map<number, Card>;
  /** The rounds and clips the cards were built for; other ones rebuild them. */
  built: string;
  handlers: TakeawayHandlers | null;
  /** The round taken from its button: the choice line gets the focus once it is chosen. */
  taking: number | null;
}

const views = new WeakMap<Element, View>();
const WATCH = "Point at a clip, or press its play button, to watch that round's agent";
const OWNER_NOTE = `The last round is not always the best. ${WATCH}; the download is the agent you take.`;
const OTHERS_NOTE = `${WATCH}. The session's owner chooses which one the download is.`;

export function renderTakeaway(element: HTMLElement, data: TakeawayData, handlers: TakeawayHandlers): void {
  const view = memo(views, element, () => build(element));
  view.handlers = handlers;
  const rounds = takeawayRounds(data.agent);
  const built = rounds.map((r) => `${r.round}:${r.clip ? data.clipUrl(r.round) : ""}`).join("|");
  if (view.built !== built) {
    view.built = built;
    for (const card of view.cards.values()) card.video?.pause();
    view.cards = new Map(rounds.map((r) => [r.round, buildCard(view, r, data.clipUrl(r.round))]));
    view.list.replaceChildren(...[...view.cards.values()].map((c) => c.item));
  }
  text(view.choice, choiceText(data.agent));
  text(view.error, data.error ?? "");
  view.error.hidden = data.error === null;
  for (const r of rounds) updateCard(view.cards.get(r.round)!, r, data.pending, data.busy, data.owner);
  text(view.note, data.owner ? OWNER_NOTE : OTHERS_NOTE);
  if (view.taking !== null && data.pending === null) {
    // The button pressed is gone with the pick (or stays on a failure): keep the focus near.
    const card = view.cards.get(view.taking);
    if (data.agent.round === view.taking) view.choice.focus();
    else if (card && !card.take.disabled) card.take.focus();
    view.taking = null;
  }
}

function updateCard(card: Card, r: TakeawayRound, pending: number | null, busy: boolean, owner: boolean): void {
  card.item.classList.toggle("chosen", r.chosen);
  attr(card.item, "aria-current", r.chosen ? "true" : null);
  text(card.score, r.score ?? "not evaluated");
  card.score.classList.toggle("muted", r.score === null);
  card.mark.hidden = !r.chosen;
  card.take.hidden = r.chosen || !owner;
  card.take.disabled = r.blocked !== null || pending !== null || busy;
  attr(card.take, "aria-busy", pending === r.round ? "true" : null);
  text(card.take, pending === r.round ? "Taking…" : "Take this agent");
  text(card.blocked, r.blocked ?? "");
  card.blocked.hidden = r.blocked === null || !owner;
}

function buildCard(view: View, r: TakeawayRound, src: string): Card {
  const name = `Round ${r.round}${r.last ? " (last)" : ""}`;
  const titleId = `takeaway-round-${r.round}`;
  let video: HTMLVideoElement | null = null;
  let play: HTMLButtonElement | null = null;
  let clip: HTMLElement;
  if (r.clip) {
    video = h("video", {
      class: "takeaway-video",
      src,
      muted: true,
      loop: true,
      playsinline: true,
      preload: "metadata",
      "aria-label": `Round ${r.round}'s agent: one greedy episode`,
    });
    video.muted = true;
    play = h("button", {
      type: "button",
      class: "takeaway-play",
      "aria-pressed": "false",
      "aria-label": `Play round ${r.round}'s clip`,
    });
    clip = h("div", { class: "takeaway-clip" }, video, play);
  } else {
    clip = h("div", { class: "takeaway-clip empty" }, h("span", { class: "muted" }, "No clip of this round"));
  }
  const score = h("p", { class: "takeaway-score num" });
  const mark = h("p", { class: "takeaway-mark" }, "✓ Chosen");
  const take = h(
    "button",
    { type: "button", class: "takeaway-take", "aria-describedby": titleId },
    "Take this agent",
  );
  const blocked = h("p", { class: "takeaway-blocked muted" });
  const item = h(
    "li",
    { class: "takeaway-round", "aria-labelledby": titleId, "data-round": r.round },
    clip,
    h(
      "div",
      { class: "takeaway-text" },
      h("p", { class: "takeaway-name", id: titleId }, h("strong", {}, name)),
      h("p", { class: "takeaway-kind muted" }, r.kind),
      score,
    ),
    mark,
    take,
    blocked,
  );
  const card: Card = { item, video, play, score, mark, take, blocked, pinned: false };
  if (video && play) {
    const v = video;
    const start = () => {
      for (const other of view.cards.values()) if (other !== card) stop(other);
      void v.play().catch(() => undefined); // a clip that cannot play stays on its first frame
      setPlaying(card, true);
    };
    clip.addEventListener("mouseenter", () => {
      if (!card.pinned) start();
    });
    clip.addEventListener("mouseleave", () => {
      if (!card.pinned) stop(card);
    });
    const toggle = () => {
      if (card.pinned) stop(card);
      else {
        start();
        card.pinned = true;
      }
    };
    play.addEventListener("click", toggle);
    v.addEventListener("click", toggle);
  }
  take.addEventListener("click", () => {
    view.taking = r.round;
    view.handlers?.pick(r.round);
  });
  return card;
}

function stop(card: Card): void {
  card.pinned = false;
  card.video?.pause();
  setPlaying(card, false);
}

/** A toggle button keeps its name ("Play round 3's clip"); aria-pressed says it plays. */
function setPlaying(card: Card, playing: boolean): void {
  if (!card.play) return;
  attr(card.play, "aria-pressed", String(playing));
  card.item.classList.toggle("playing", playing);
}

function build(element: HTMLElement): View {
  const note = h("p", { class: "takeaway-note muted" });
  const choice = h("p", { class: "takeaway-choice", tabindex: -1, "aria-live": "polite" });
  const error = h("p", { class: "takeaway-error", role: "alert", hidden: true });
  const list = h("ul", { class: "takeaway-list", "aria-label": "The rounds' agents" });
  element.classList.add("takeaway");
  element.setAttribute("aria-labelledby", "takeaway-title");
  element.replaceChildren(
    h("h3", { class: "chart-title", id: "takeaway-title" }, "Choose the agent you take away"),
    note,
    choice,
    error,
    list,
  );
  return { note, choice, error, list, cards: new Map(), built: "", handlers: null, taking: null };
}
