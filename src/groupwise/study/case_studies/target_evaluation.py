"""Scoring a policy on a target: whole episodes in a target env, each scored by the env's own
total, with their actions kept so that one can be filmed (`study.case_studies.film`)."""

from dataclasses import dataclass

import numpy as np

from groupwise.envs import TARGET_TOTAL_KEY, Target
from groupwise.envs.targets import TARGET_SCORE_KEY
from groupwise.rl.policy import Policy
from groupwise.rl.rollout import EnvFactory
from groupwise.types import FloatArray


@dataclass(frozen=True)
class TargetEvaluation:
    """Episodes of a policy scored by a target (their actions kept for filming)."""

    scores: FloatArray  # (E,) episode target scores
    returns: FloatArray  # (E,) sums of the per-step scores (the env's true return)
    reset_seeds: tuple[int, ...]  # (E,)
    actions: tuple[np.ndarray, ...]  # E × (T, *action_shape) raw env actions
    step_scores: tuple[FloatArray, ...]  # E × (T,)

    def success_rate(self, target: Target) -> float:
        return float(np.mean([target.succeeds(s) for s in self.scores]))

    def stretch_rate(self, target: Target) -> float:
        return float(np.mean([target.stretches(s) for s in self.scores]))

    def summary(self, target: Target) -> dict[str, float]:
        """The target score's mean and sd, the success and stretch rates and the mean sum
        of step scores, under the names of `CaseRecord`'s columns."""
        return {
            "target_score_mean": float(self.scores.mean()),
            "target_score_std": float(self.scores.std()),
            "success_rate": self.success_rate(target),
            "stretch_rate": self.stretch_rate(target),
            "true_return_mean": float(self.returns.mean()),
        }


def evaluate_target(
    make_env: EnvFactory, policy: Policy, n_episodes: int, rng: np.random.Generator
) -> TargetEvaluation:
    """`n_episodes` whole episodes of `policy` side by side in a target env from `make_env`,
    each reset with a seed drawn from `rng`; the score of each is the env's
    ``info["target_total"]`` at its last step.

    Raises:
        ValueError: `n_episodes` < 1.
    """
    if n_episodes < 1:
        raise ValueError(f"need at least one episode, got {n_episodes}")
    envs = [make_env() for _ in range(n_episodes)]
    seeds = [int(s) for s in rng.integers(0, 2**31 - 1, size=n_episodes)]
    try:
        obs = np.stack([env.reset(seed=s)[0] for env, s in zip(envs, seeds, strict=True)])
        actions: list[list[np.ndarray]] = [[] for _ in envs]
        scores: list[list[float]] = [[] for _ in envs]
        totals = np.zeros(n_episodes)
        running = list(range(n_episodes))
        while running:
            batch = np.asarray(policy.act(obs[running].astype(np.float32), rng))
            still = []
            for i, action in zip(running, batch, strict=True):
                obs[i], _, terminated, truncated, info = envs[i].step(action)
                actions[i].append(action)
                scores[i].append(float(info[TARGET_SCORE_KEY]))
                totals[i] = info[TARGET_TOTAL_KEY]
                if not (terminated or truncated):
                    still.append(i)
            running = still
    finally:
        for env in envs:
            env.close()
    steps = tuple(np.asarray(s) for s in scores)
    return TargetEvaluation(
        scores=totals,
        returns=np.array([s.sum() for s in steps]),
        reset_seeds=tuple(seeds),
        actions=tuple(np.asarray(a) for a in actions),
        step_scores=steps,
    )
