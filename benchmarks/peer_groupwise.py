"""One peer-benchmark cell of groupwise (run by `benchmarks/peer.py` in the project's venv).

    python benchmarks/peer_groupwise.py '<cell spec JSON>'   → one JSON line on stdout

The library as a user would run it (`PreferenceComparisons`) with our PPO adapter, pairwise
active learning (`PairwiseQueries`) and the spec's teacher: Boltzmann without perception
noise (`PairwiseTeacher(sigma=0, beta)`, imitation's `SyntheticGatherer`), or with
`"noise": "spec"` SPEC §7's perception noise (`PairwiseTeacher(sigma)`). A `variant` names
changes to the defaults for ablations (`VARIANTS`).
"""

import dataclasses
import json
import sys
import time
from typing import Any

import numpy as np
import torch

from groupwise.config import LoopConfig, PPOConfig, RewardConfig
from groupwise.envs import make_env
from groupwise.query.strategies import PairwiseQueries
from groupwise.reward import RewardEnsemble
from groupwise.rl.ppo import PPOAgent
from groupwise.run.preference_comparisons import PreferenceComparisons
from groupwise.teachers import Feedback, PairwiseTeacher
from peer_eval import episode_returns

VARIANTS: dict[str, dict[str, dict[str, Any]]] = {
    "default": {},
    "epochs10": {"reward": {"epochs": 10}},
    "fresh": {"reward": {"warm_start": False, "epochs": 10}},
    "std-out": {"reward": {"standardise_output": True}},
    "std-out-noppo": {"reward": {"standardise_output": True}, "ppo": {"normalize_reward": False}},
    "reset-norm": {"ppo": {"reset_reward_norm": True}},
    "no-val": {"reward": {"validation_fraction": 0.0}},
    "init30": {"loop": {"initial_fraction": 0.3}},
    "batch32": {"reward": {"batch_size": 32, "epochs": 10}},
    "random-windows": {"loop": {"pool_selection": "random"}},
    "oversample4": {"loop": {"pool_oversample": 4.0}},
    "obs-only": {"reward": {"use_actions": False}},
    "batch32-e3": {"reward": {"batch_size": 32}},
    # imitation's reward training: 32 pairs a minibatch, no validation split (no adaptive L2)
    "imitation-fit": {"reward": {"batch_size": 32, "validation_fraction": 0.0}},
    # imitation's reward for PPO: running per-step centring and scaling, no return scaling
    # (the default since issue 41)
    "std-step": {"ppo": {"standardise_reward": True, "normalize_reward": False}},
    # the default before issue 41: the learned reward scaled by the running return std
    "return-scale": {"ppo": {"standardise_reward": False}},
    "joint": {"reward": {"action_term": "joint"}},  # SPEC §3's one MLP, the old default
    "additive": {"reward": {"action_term": "additive"}},
    "cost": {"reward": {"action_term": "cost"}},
    # the ceiling: the same loop and labels, but PPO on the env's own reward
    "true-reward": {},
}
"""Variant name → {"loop" | "reward" | "ppo": field overrides} on top of the spec."""
TRUE_REWARD_VARIANT = "true-reward"


def evaluate(agent: PPOAgent, make, seeds: list[int]) -> list[float]:
    policy = agent.policy(deterministic=True)
    rng = np.random.default_rng(0)
    return episode_returns(lambda obs: policy.act(obs, rng), make, seeds)


def reward_correlations(
    comparisons: PreferenceComparisons, reward: RewardConfig, make, seed: int
) -> dict[str, float]:
    """Per-state Pearson correlation of the learned reward with the true reward, for the
    loop's ensemble and for a fresh ensemble fitted from scratch (30 epochs) on the same
    pairs, over steps of 20 episodes of a random policy mixed with the final agent's."""
    from groupwise.reward import fit
    from groupwise.rl.policy import RandomPolicy
    from groupwise.rl.rollout import sample_trajectories

    rng = np.random.default_rng([seed, 7])
    agent = comparisons.run.agent
    episodes = sample_trajectories(make, RandomPolicy(make().action_space), 10, rng)
    episodes += sample_trajectories(make, agent.policy(), 10, rng)
    obs = np.concatenate([t.obs for t in episodes])
    acts = np.concatenate([t.acts for t in episodes])
    true = np.concatenate([t.true_rewards for t in episodes])
    loop_reward = comparisons.run.ensemble.step_rewards(obs, acts).mean(axis=0)
    fresh = RewardEnsemble.for_env(make, reward, np.random.default_rng([seed, 8]))
    fit(fresh, comparisons.dataset, reward, np.random.default_rng([seed, 9]), 30)
    fresh_reward = fresh.step_rewards(obs, acts).mean(axis=0)
    ppo_reward = comparisons.run.ensemble.mean_reward(obs, acts)  # what PPO is given
    return {
        "reward_corr": float(np.corrcoef(loop_reward, true)[0, 1]),
        "fresh_fit_corr": float(np.corrcoef(fresh_reward, true)[0, 1]),
        # the learned reward's offset against its spread over these steps: a large offset
        # inflates the return std PPO's reward normaliser divides by
        "reward_mean_over_sd": float(ppo_reward.mean() / ppo_reward.std()),
        **health_gaps(make, obs, loop_reward, true),
    }


def health_gaps(make, obs: np.ndarray, learned: np.ndarray, true: np.ndarray) -> dict:
    """On a locomotion env that pays for staying healthy (Hopper, Walker2d: height and torso
    angle in range), how much more a healthy step earns than a fallen one, in sds of each
    reward over the same steps: does the learned reward pay for not falling as the true one
    does? Empty on other envs."""
    env = make()
    z_range = getattr(env.unwrapped, "_healthy_z_range", None)
    angle_range = getattr(env.unwrapped, "_healthy_angle_range", None)
    env.close()
    if z_range is None or angle_range is None:
        return {}
    healthy = (
        (obs[:, 0] > z_range[0])
        & (obs[:, 0] < z_range[1])
        & (obs[:, 1] > angle_range[0])
        & (obs[:, 1] < angle_range[1])
    )
    if healthy.all() or not healthy.any():
        return {"healthy_share": float(healthy.mean())}

    def gap(r: np.ndarray) -> float:
        return float((r[healthy].mean() - r[~healthy].mean()) / r.std())

    return {
        "healthy_share": float(healthy.mean()),
        "health_gap": gap(learned),
        "true_health_gap": gap(true),
    }


def main(spec: dict) -> dict:
    started = time.perf_counter()
    torch.set_num_threads(1)
    seed, variant = spec["seed"], spec.get("variant", "default")
    changes = VARIANTS[variant]

    def make():
        return make_env(spec["env"], **spec.get("env_kwargs", {}))

    loop = LoopConfig(
        env=spec["env"],
        comparisons=spec["comparisons"],
        rounds=spec["rounds"],
        steps=spec["steps_per_round"] * spec["rounds"],
        initial_fraction=spec["initial_fraction"],
        fragment_length=spec["fragment_length"],
        exploration_fraction=spec["exploration_fraction"],
        candidate_pairs=spec["candidate_pairs"],
        eval_episodes=len(spec["eval_seeds"]),
        seed=seed,
    )
    loop = dataclasses.replace(loop, **changes.get("loop", {}))
    reward = dataclasses.replace(
        RewardConfig(
            ensemble_size=spec["ensemble_size"], hidden_sizes=tuple(spec["reward_hidden"])
        ),
        **changes.get("reward", {}),
    )
    ppo = dataclasses.replace(
        PPOConfig(**{**spec["ppo"], "net_arch": tuple(spec["ppo"]["net_arch"])}, tensorboard=False),
        **changes.get("ppo", {}),
    )
    ensemble = RewardEnsemble.for_env(make, reward, np.random.default_rng([seed, 2**20]))
    on_true_reward = variant == TRUE_REWARD_VARIANT
    agent = PPOAgent(
        make, ppo, seed=seed, reward_fn=None if on_true_reward else ensemble.mean_reward
    )
    ppo_seconds = [0.0]
    learn = agent.learn

    def timed_learn(*args: Any, **kwargs: Any) -> None:
        tick = time.perf_counter()
        learn(*args, **kwargs)
        ppo_seconds[0] += time.perf_counter() - tick

    agent.learn = timed_learn  # type: ignore[method-assign]  # timed in place
    if spec.get("noise", "boltzmann") == "spec":  # SPEC §7: perceived returns, the higher wins
        teacher = PairwiseTeacher(sigma=spec["sigma"])
    else:
        teacher = PairwiseTeacher(sigma=0.0, beta=spec["boltzmann_beta"])
    feedback = Feedback(PairwiseQueries(candidates=loop.candidate_pairs), teacher)
    curve: list[float] = []
    seeds = spec["eval_seeds"]
    # per-round curve on the same reset seeds as the final evaluation
    loop_eval = dataclasses.replace(loop, eval_episodes=0)
    comparisons = PreferenceComparisons(make, agent, ensemble, feedback, loop_eval, reward)
    comparisons.train(on_round=lambda _: curve.append(float(np.mean(evaluate(agent, make, seeds)))))
    final = evaluate(agent, make, seeds)
    wall = time.perf_counter() - started
    correlations = reward_correlations(comparisons, reward, make, seed)
    records = comparisons.records
    return {
        "side": "groupwise",
        "env": spec["env"],
        "seed": seed,
        "variant": variant,
        "wall_s": wall,
        "ppo_s": ppo_seconds[0],
        "non_ppo_s": wall - ppo_seconds[0],
        "final_return": float(np.mean(final)),
        "curve": curve,
        "env_steps": int(agent.num_timesteps),
        "label_error": float(records[-1].label_error_rate_total),
        "pairs": int(records[-1].pairs_total),
        **correlations,
    }


if __name__ == "__main__":
    print(json.dumps(main(json.loads(sys.argv[1]))))
