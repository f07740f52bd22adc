"""PPO env steps per second on the true reward vs on the learned reward (same run).

The ratio is the overhead of querying the reward ensemble at every env step. Times are
this process's CPU time (one torch thread), so other load on the machine distorts them less.
Run: `python benchmarks/ppo_throughput.py` (or `python -m benchmarks ppo_throughput`).
"""

import time

import numpy as np
import torch

from groupwise.config import PPOConfig, RewardConfig
from groupwise.envs import make_env
from groupwise.envs.spaces import action_dim, observation_dim
from groupwise.reward import RewardEnsemble
from groupwise.rl.ppo import PPOAgent

ENVS = ["GridWorld", "Hopper"]
STEPS = 8 * 256 * 4


def steps_per_second(env: str, learned: bool) -> float:
    cfg = PPOConfig(tensorboard=False)
    probe = make_env(env)
    obs_dim, act_dim = observation_dim(probe.observation_space), action_dim(probe.action_space)
    probe.close()
    reward_fn = None
    if learned:
        ensemble = RewardEnsemble(obs_dim, act_dim, RewardConfig(), np.random.default_rng(0))
        reward_fn = ensemble.mean_reward
    agent = PPOAgent(lambda: make_env(env), cfg, seed=0, reward_fn=reward_fn)
    agent.learn(cfg.n_envs * cfg.n_steps, seed=0)  # warm-up rollout
    start = time.process_time()
    agent.learn(STEPS, seed=1)
    seconds = time.process_time() - start
    agent.close()
    return STEPS / seconds


REPEATS = 3


def main() -> None:
    torch.set_num_threads(1)
    print(f"{STEPS} PPO steps per measurement (CPU time), median of {REPEATS} repeats\n")
    print("| env | PPO, true reward (steps/s) | PPO, learned reward (steps/s) | ratio |")
    print("|---|---:|---:|---:|")
    for env in ENVS:
        runs = [(steps_per_second(env, False), steps_per_second(env, True)) for _ in range(REPEATS)]
        true, learned = np.median(np.array(runs), axis=0)
        print(f"| {env} | {true:,.0f} | {learned:,.0f} | {learned / true:.2f} |", flush=True)


if __name__ == "__main__":
    main()
