/**
 * Looping, muted clips that start together (SPEC §9: synchronised start, adjustable speed),
 * loaded a few at a time (`loadClips`).
 */
import { LoadLimiter, type Place } from "../lib/load-limiter";
import { h } from "./dom";

/**
 * Clip requests the page lets run at once. A browser keeps 6 HTTP/1.1 connections to a server
 * and the page's event stream holds one; a clip the server renders on demand (issue 22) holds
 * its connection until its first bytes, and a group of 8 took 2.3–5.7 s to its last on a busy
 * machine, so 8 or 16 clips at once made every API call (a judgement, undo, the Annotators
 * dialog) wait behind them, ~10 s once. 3 leaves 2 connections for the API and still keeps the
 * server's 2 render processes (`AppConfig.clip_workers`) busy.
 */
export const CLIP_REQUESTS_IN_FLIGHT = 3;

/** Sources of the videos that wait for a slot: set by `setClipSource`, taken by `begin`. */
const pending = new WeakMap<HTMLVideoElement, string>();
const wired = new WeakSet<HTMLVideoElement>();
const limiter = new LoadLimiter<HTMLVideoElement>(CLIP_REQUESTS_IN_FLIGHT, begin);
/** Events that end a clip's request: its first frame (or more) arrived, it failed, it stopped. */
const LOAD_ENDS = ["loadeddata", "canplay", "error", "abort"] as const;

function begin(video: HTMLVideoElement): void {
  const src = pending.get(video);
  pending.delete(video);
  if (src === undefined) {
    limiter.release(video);
    return;
  }
  // Setting the source resets the rate to the default one (the HTML media element load
  // algorithm), and `startTogether` may have set the comparison's speed on it meanwhile.
  video.defaultPlaybackRate = video.playbackRate;
  video.src = src;
}

function loadEnded(event: Event): void {
  const video = event.currentTarget as HTMLVideoElement;
  // Only a request in flight ends: a late "abort" of a source replaced meanwhile must not drop
  // the new one from the queue, and "canplay" fires again after every seek of a loop.
  if (limiter.loading.has(video)) limiter.release(video);
}

/**
 * Gives `video` the clip `src` to load when `loadClips` lets it ("": none). A source it had
 * is dropped, and its request with it.
 */
export function setClipSource(video: HTMLVideoElement, src: string): void {
  if (video.hasAttribute("src") || pending.has(video) || limiter.loading.has(video)) unloadVideo(video);
  if (!wired.has(video)) {
    wired.add(video);
    for (const type of LOAD_ENDS) video.addEventListener(type, loadEnded);
  }
  if (src) pending.set(video, src);
}

/**
 * Asks for the clips of `videos` (those given a source by `setClipSource` and not asked for
 * yet, or still waiting), at most `CLIP_REQUESTS_IN_FLIGHT` at once. The batch goes ahead of
 * the clips still waiting (`"first"`: what the person looks at now) or behind them (`"last"`:
 * a prefetch); a video's poster shows until its clip plays.
 */
export function loadClips(videos: Iterable<HTMLVideoElement>, place: Place = "first"): void {
  limiter.request(
    [...videos].filter((v) => pending.has(v)),
    place,
  );
}

/** A looping, muted clip with its poster; its clip loads when `loadClips` asks for it. */
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
  setClipSource(video, src);
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
 * image loads as soon as the element exists, so a prefetched clip has its poster ready; the
 * clip loads when `loadClips` asks for it.
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

/** Releases a video's decoder, and its clip request or place in the queue, before it is dropped. */
export function unloadVideo(video: HTMLVideoElement): void {
  pending.delete(video);
  limiter.release(video);
  video.pause();
  video.removeAttribute("src");
  video.load();
}
