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
  evaluate: "Measuring the agent's true return",
};

export function phaseName(phase: string): string {
  return PHASES[phase] ?? phase.charAt(0).toUpperCase() + phase.slice(1).replace(/[_-]/g, " ");
}
