"""Fresh PPO (the run's settings, 204,800 steps) on a run's round-R learned reward: does that reward teach the target?

python replay.py RUN_DIR ROUND SEED [STEPS]
"""

import sys
from pathlib import Path

import numpy as np

from groupwise.config import RunConfig
from groupwise.envs import TARGETS, make_env
from groupwise.reward import RewardEnsemble
from groupwise.rl.ppo import PPOAgent
from groupwise.run.checkpoint import REWARD_FILE, checkpoint_dir
from groupwise.study.case_study import evaluate_target

run, rnd, seed = Path(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
steps = int(sys.argv[4]) if len(sys.argv) > 4 else 204800
cfg = RunConfig.load(run / "config.json")
target = next(t for t in TARGETS.values() if t.env == cfg.loop.env)
ens = RewardEnsemble.load(checkpoint_dir(run, rnd) / REWARD_FILE)


def make():
    return make_env(target.env)


agent = PPOAgent(make, cfg.ppo, seed=seed, reward_fn=ens.mean_reward)
rng = np.random.default_rng(seed)
first = True
out = []
while agent.num_timesteps < steps:
    agent.learn(40960, seed if first else None)
    first = False
    ev = evaluate_target(make, agent.policy(deterministic=True), 5, rng)
    s = ev.summary(target)
    out.append((agent.num_timesteps, round(s["target_score_mean"], 2), s["success_rate"]))
    print(run.name, rnd, seed, out[-1], flush=True)
