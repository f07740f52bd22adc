/**
 * The floating clip preview beside the pointer (SPEC §9): a leaf's clip, or a cluster's size
 * and up to three representative clips (its medoids), with how long a clip is and how fast
 * it plays ("1.5 s · real speed", as by the comparison's clips). Videos are muted, looping, and
 * unloaded when the preview hides, so sweeping over the chart does not pile up decoders.
 * It stays inside the area `bounds` gives (the chart's), so it never covers the controls
 * beside the chart, such as the answer buttons.
 */
import { clipCaption } from "../lib/clip-timing";
import { type Bounds, placeBeside } from "../lib/tooltip";
import type { TreeNode } from "../lib/tree";
import type { RoundData } from "../state";
import { loadClips, setClipSource, unloadVideo } from "./clips";
import { h, text } from "./dom";

export interface PreviewClip {
  id: string;
  src: string;
  poster?: string;
}

export interface PreviewContent {
  /** Identity: the same key keeps the playing videos. */
  key: string;
  title: string;
  detail: string;
  clips: PreviewClip[];
  /** How long each clip is and how fast it plays, e.g. "1.5 s · real speed" ("": not known). */
  timing: string;
  /** Large single clip (a leaf) or a row of small ones (a cluster). */
  large: boolean;
}

export interface Preview {
  show(content: PreviewContent, x: number, y: number): void;
  move(x: number, y: number): void;
  hide(): void;
  readonly element: HTMLElement;
}

const OFFSET = 18;
const MARGIN = 8;

/**
 * `bounds`: the area (viewport pixels) the preview must stay in; the viewport when omitted.
 */
export function createPreview(parent: HTMLElement = document.body, bounds?: () => Bounds): Preview {
  const title = h("div", { class: "preview-title" });
  const detail = h("div", { class: "preview-detail" });
  const clips = h("div", { class: "preview-clips" });
  const timing = h("div", { class: "preview-timing clip-timing" });
  const element = h("div", { class: "preview", role: "tooltip", hidden: true }, title, detail, clips, timing);
  parent.append(element);
  let key: string | null = null;

  function unload(): void {
    for (const v of clips.querySelectorAll("video")) unloadVideo(v);
    clips.replaceChildren();
  }

  function place(x: number, y: number): void {
    const view = {
      left: MARGIN,
      top: MARGIN,
      right: document.documentElement.clientWidth - MARGIN,
      bottom: document.documentElement.clientHeight - MARGIN,
    };
    const area = bounds?.();
    const box = area
      ? {
          left: Math.max(view.left, area.left),
          top: Math.max(view.top, area.top),
          right: Math.min(view.right, area.right),
          bottom: Math.min(view.bottom, area.bottom),
        }
      : view;
    const { left, top } = placeBeside(x, y, element.offsetWidth, element.offsetHeight, box, OFFSET);
    element.style.transform = `translate(${left}px, ${top}px)`;
  }

  return {
    element,
    show(content, x, y) {
      if (content.key !== key) {
        unload();
        key = content.key;
        element.classList.toggle("large", content.large);
        const videos: HTMLVideoElement[] = [];
        for (const clip of content.clips) {
          const video = h("video", {
            muted: true,
            loop: true,
            autoplay: true,
            playsinline: true,
            preload: "auto",
            poster: clip.poster,
            "aria-label": `clip of behaviour ${clip.id}`,
          });
          video.muted = true; // the attribute alone does not mute a script-made video
          setClipSource(video, clip.src);
          videos.push(video);
          void video.play().catch(() => undefined);
          clips.append(h("figure", {}, video, h("figcaption", {}, clip.id)));
        }
        loadClips(videos); // what the pointer is on goes ahead of clips asked for before
      }
      text(title, content.title);
      text(detail, content.detail);
      text(timing, content.timing);
      timing.hidden = !content.timing || content.clips.length === 0;
      element.hidden = false;
      place(x, y);
    },
    move(x, y) {
      if (!element.hidden) place(x, y);
    },
    hide() {
      if (element.hidden) return;
      element.hidden = true;
      key = null;
      unload();
    },
  };
}

/** Up to three representative behaviours of a node: its medoids, else its first leaves. */
export function medoidsOf(round: RoundData, node: TreeNode): string[] {
  // Padding nodes ("{id}@{level}") repeat the real node below them.
  for (let n: TreeNode | undefined = node; n; n = n.children.length === 1 ? n.children[0] : undefined) {
    const m = round.medoids[n.id] ?? round.medoids[n.id.split("@")[0]!];
    if (m && m.length) return m.slice(0, 3);
  }
  return node.leaves.slice(0, 3);
}

/**
 * What the preview shows for an arc: a behaviour's clip (a leaf, or a padding arc standing
 * for one), or a cluster's size, group shares and up to three medoid clips.
 */
export function previewContent(
  round: RoundData,
  node: TreeNode,
  counts: { A: number; B: number } | undefined,
  compared: ReadonlySet<string>,
  clipUrl: (clip: string) => string,
): PreviewContent {
  const clipOf = (id: string): PreviewClip | null => {
    const leaf = round.tree.nodes.get(id);
    if (!leaf?.clip) return null;
    const clip: PreviewClip = { id, src: clipUrl(leaf.clip) };
    if (leaf.poster) clip.poster = clipUrl(leaf.poster);
    return clip;
  };
  // The preview's videos play at their own rate, whatever the comparison's speed control says.
  const timing = clipCaption(round.clip);
  const n = node.leaves.length;
  if (n === 1) {
    const id = node.leaves[0]!;
    const where = counts?.A ? "in group A" : counts?.B ? "in group B" : "in no group";
    const seen = compared.has(id) ? "compared before" : "not compared yet";
    const clip = clipOf(id);
    return {
      key: node.id,
      title: `behaviour ${id}`,
      detail: `${node.isLeaf ? "" : `level ${node.level} · `}${where} · ${seen}`,
      clips: clip ? [clip] : [],
      timing,
      large: true,
    };
  }
  const fresh = node.leaves.filter((id) => !compared.has(id)).length;
  const parts = [`level ${node.level}`];
  if (counts?.A) parts.push(`${counts.A} in A`);
  if (counts?.B) parts.push(`${counts.B} in B`);
  parts.push(`${fresh} not compared yet`);
  return {
    key: node.id,
    title: `cluster of ${n} behaviours`,
    detail: parts.join(" · "),
    clips: medoidsOf(round, node).map(clipOf).filter((x): x is PreviewClip => x !== null),
    timing,
    large: false,
  };
}
