/**
 * What a clip shows, in words: the simulated time it covers and how fast it plays
 * (docs/app.md, "Clips"). The server gives each pool's timing; the page's speed control
 * multiplies the clip's own playback speed (1.0: real speed).
 */

/** The fields of the API's `ClipTiming` this needs. */
export interface ClipTimingLike {
  seconds: number;
  speed: number;
}

/** "1.5 s", "0.24 s", "2 s": two significant digits at most. */
export function seconds(value: number): string {
  return `${Number(value.toPrecision(2))} s`;
}

/** The caption by the clips, e.g. "1.5 s · real speed" or "1.5 s · 0.5× real speed"
 * (`rate` is the page's playback rate); "" without a timing (pools prepared before it). */
export function clipCaption(timing: ClipTimingLike | null | undefined, rate = 1): string {
  if (!timing) return "";
  const speed = Number((timing.speed * rate).toPrecision(3));
  const played = speed === 1 ? "real speed" : `${speed}× real speed`;
  return `${seconds(timing.seconds)} · ${played}`;
}
