/** Looping, muted clips that start together (SPEC §9: synchronised start, adjustable speed). */
import { h } from "./dom";

export function clipVideo(src: string, poster: string | undefined, label: string): HTMLVideoElement {
  const video = h("video", {
    muted: true,
    loop: true,
    playsinline: true,
    preload: "auto",
    poster,
    "aria-label": label,
  });
  video.muted = true;
  video.src = src;
  return video;
}

/** A clip in a frame that shows its poster until the clip plays (`posterClip`). */
export interface PosterClip {
  frame: HTMLElement;
  video: HTMLVideoElement;
}

/**
 * A clip that shows its poster until it plays: the poster image lies in the flow and sizes
 * the frame (a poster is a frame of the clip, so the clip's own size), the video lies over it,
 * transparent until its first "playing" (issue 23: a new pairwise clip showed an empty box
 * before its first frame, while the video element's own poster was not loaded yet). The
 * image loads as soon as the element exists, so a prefetched clip has its poster ready.
 */
export function posterClip(src: string, poster: string, label: string): PosterClip {
  const video = clipVideo(src, poster, label);
  const frame = h("div", { class: "clip-frame" }, h("img", { class: "clip-poster", src: poster, alt: "" }), video);
  video.addEventListener("playing", () => {
    frame.dataset.playing = "";
  });
  return { frame, video };
}

/**
 * How long `startTogether` waits for every clip to be playable. Clips are rendered by the server
 * when first asked for (issue 22: ~0.4 s a 1.5 s Hopper clip, a group of 8 within 1–6 s on 2
 * busy cores, posters shown meanwhile), so a group's clips may arrive seconds apart.
 */
const READY_TIMEOUT_MS = 6000;

function whenReady(video: HTMLVideoElement): Promise<void> {
  if (video.readyState >= HTMLMediaElement.HAVE_FUTURE_DATA) return Promise.resolve();
  return new Promise((resolve) => {
    const done = () => {
      video.removeEventListener("canplay", done);
      video.removeEventListener("error", done);
      resolve();
    };
    video.addEventListener("canplay", done);
    video.addEventListener("error", done);
  });
}

let generation = 0;

/**
 * Rewinds the videos and starts them in the same frame once all can play (or after a
 * timeout, so one broken clip does not hold the others). A later call cancels an earlier
 * one still waiting.
 */
export async function startTogether(videos: HTMLVideoElement[], rate: number): Promise<void> {
  const mine = ++generation;
  for (const v of videos) {
    v.pause();
    v.playbackRate = rate;
    if (v.readyState > 0) v.currentTime = 0;
  }
  const timeout = new Promise<void>((r) => setTimeout(r, READY_TIMEOUT_MS));
  await Promise.race([Promise.all(videos.map(whenReady)), timeout]);
  if (mine !== generation) return;
  for (const v of videos) {
    if (v.readyState > 0) v.currentTime = 0;
    v.playbackRate = rate;
    void v.play().catch(() => undefined);
  }
}

export function setRate(videos: Iterable<HTMLVideoElement>, rate: number): void {
  for (const v of videos) if (v.playbackRate !== rate) v.playbackRate = rate;
}

/** Releases a video's decoder before it is dropped. */
export function unloadVideo(video: HTMLVideoElement): void {
  video.pause();
  video.removeAttribute("src");
  video.load();
}
