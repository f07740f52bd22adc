/**
 * How the New-session page names the envs (`GET /api/envs`): the six envs, the case studies'
 * reward-free targets with what they score, and any other Gymnasium id typed in.
 */
import type { EnvInfo } from "../api";

/** The env chooser's value for "another Gymnasium id" (typed into a field of its own). */
export const OTHER_ENV = "";

function num(x: number): string {
  return Number.isInteger(x) ? String(x) : String(Number(x.toPrecision(3)));
}

/** An option's text: the name, and for a target when an episode succeeds, in words
 * ("Walker2d-splits · success: a split held ≥ 1 s"). */
export function envOptionText(env: EnvInfo): string {
  const t = env.target;
  return t ? `${env.name} · success: ${t.success}` : env.name;
}

/** One line about the chosen env (null: another Gymnasium id). */
export function envAbout(env: EnvInfo | null): string {
  if (!env) {
    return (
      "Any registered Gymnasium id (e.g. Pendulum-v1), or module:Env-v0 for one that importing " +
      "its module registers; its episodes need a fixed horizon of at least one behaviour."
    );
  }
  const t = env.target;
  if (t) {
    return (
      `Reward-free ${t.base}, scored by its target (${t.unit}); success: ${t.success}, ` +
      `stretch: ${num(t.stretch)}. ${capitalise(t.description)}.`
    );
  }
  return `${env.gym_id} · ${env.horizon} steps an episode · ${capitalise(env.description)}.`;
}

function capitalise(text: string): string {
  return text.charAt(0).toUpperCase() + text.slice(1);
}
