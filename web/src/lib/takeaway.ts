/**
 * The take-away agent (issue 20): which round's policy a finished session hands over, and
 * what the results page says of each round's agent so a person can choose among them (the
 * last round is not always the best: docs/case-studies.md, "Kept once learned"). Pure: the
 * view (`views/takeaway.ts`) only draws what these return.
 */
import type { AgentOut } from "../api";
import { plural } from "./format";
import { capitalise, meanSd } from "./results";

type Agent = Pick<AgentOut, "round" | "chosen_by" | "rounds" | "measure" | "target">;

/** One round's agent as the picker shows it. */
export interface TakeawayRound {
  round: number;
  /** False for a round without feedback: PPO on the frozen learned reward only. */
  feedback: boolean;
  /** How the round trained: "after 6 comparisons", "PPO on the frozen reward". */
  kind: string;
  /** Its evaluation, "True return 41.5 ± 3.2" (a target env: its episode score in the
   * target's unit); null for a round that was not evaluated. */
  score: string | null;
  /** The download is this round's agent. */
  chosen: boolean;
  /** The session's last round: the take-away agent until a person picks another. */
  last: boolean;
  /** The round's greedy policy was filmed (`GET …/agent/rounds/{round}.mp4`). */
  clip: boolean;
  /** Why it cannot be taken (its checkpoint is gone); null when it can. */
  blocked: string | null;
}

/** The rounds' agents in round order, the chosen one and the last marked. */
export function takeawayRounds(agent: Agent): TakeawayRound[] {
  const rounds = [...agent.rounds].sort((a, b) => a.round - b.round);
  const last = rounds.length ? rounds[rounds.length - 1]!.round : agent.round;
  return rounds.map((r) => ({
    round: r.round,
    feedback: r.feedback,
    kind: r.feedback ? `after ${plural(r.judgements, "comparison")}` : "PPO on the frozen reward",
    score: roundScore(agent, r),
    chosen: r.round === agent.round,
    last: r.round === last,
    clip: r.video,
    blocked: r.checkpoint ? null : "Its checkpoint was not kept: this agent cannot be packaged.",
  }));
}

function roundScore(agent: Agent, r: AgentOut["rounds"][number]): string | null {
  const t = agent.target;
  if (t && r.target_score_mean !== null) {
    return `${capitalise(t.unit)} ${meanSd(r.target_score_mean, r.target_score_std)}`;
  }
  if (r.true_return_mean === null) return null;
  const unit = t ? ` ${t.step_unit}` : "";
  return `${capitalise(t ? "per-step sum" : agent.measure)} ${meanSd(r.true_return_mean, r.true_return_std)}${unit}`;
}

const CHOSEN_BY: Record<AgentOut["chosen_by"], string> = {
  last: "last round",
  person: "your pick",
  teacher: "the simulated teacher's pick",
};

/** Which agent the download is, and who chose it: "Chosen: round 3 (last round)". */
export function choiceText(agent: Pick<AgentOut, "round" | "chosen_by">): string {
  return `Chosen: round ${agent.round} (${CHOSEN_BY[agent.chosen_by] ?? agent.chosen_by})`;
}
