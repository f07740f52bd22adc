/** Small formatting helpers of the views. */

/** m:ss (or h:mm:ss) of a duration in seconds. */
export function clock(seconds: number): string {
  const s = Math.max(0, Math.floor(seconds));
  const h = Math.floor(s / 3600);
  const m = Math.floor((s % 3600) / 60);
  const ss = String(s % 60).padStart(2, "0");
  return h > 0 ? `${h}:${String(m).padStart(2, "0")}:${ss}` : `${m}:${ss}`;
}

/** Seconds on a round's timer now, from a snapshot taken `sinceMs` ago. */
export function elapsedNow(
  timer: { elapsed_s: number; paused: boolean; running?: boolean },
  sinceMs: number,
): number {
  const running = timer.running ?? !timer.paused;
  return running ? timer.elapsed_s + Math.max(0, sinceMs) / 1000 : timer.elapsed_s;
}

export function plural(n: number, one: string, many = `${one}s`): string {
  return `${n.toLocaleString("en")} ${n === 1 ? one : many}`;
}

/** Names of the worker's phases (SessionState.progress.phase) for people. */
const PHASES: Record<string, string> = {
  sample: "Sampling behaviours",
  sampling: "Sampling behaviours",
  render: "Rendering clips",
  clips: "Rendering clips",
  distances: "Measuring distances between behaviours",
  dtw: "Measuring distances between behaviours",
  tree: "Clustering behaviours",
  suggestions: "Computing suggestions",
  prepare: "Preparing the next behaviours",
  preparing: "Preparing the next behaviours",
  reward: "Training the reward model",
  ppo: "Training the agent (PPO)",
  policy: "Training the agent (PPO)",
  checkpoint: "Saving a checkpoint",
  eval: "Measuring the agent's true return",
  video: "Filming the final agent",
  package: "Packing the agent for download",
  evaluate: "Measuring the agent's true return",
};

export function phaseName(phase: string): string {
  return PHASES[phase] ?? phase.charAt(0).toUpperCase() + phase.slice(1).replace(/[_-]/g, " ");
}

/**
 * A round as people read it: "2 of 0–4". Rounds are numbered from 0 on the page as in the
 * API, the export and the checkpoint folders (`round-0000`), so every place a person reads
 * a round number agrees (docs/app.md, "Round numbering").
 */
export function roundOf(round: number, rounds: number): string {
  const last = Math.max(0, rounds - 1);
  return last === 0 ? `${round} (the only one)` : `${Math.min(round, last)} of 0–${last}`;
}

/** The question an answer replies to, in both modes' words. */
export function question(of: "group" | "clip"): string {
  return `Which ${of} is closer to the behaviour you want?`;
}
