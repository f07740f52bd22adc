"""The learned return of a run's final reward on 3 episodes each of a backflipping policy
(refpol.py), the run's own final greedy policy and a random one.

    python rank.py RUN_DIR ...
"""

import sys
from pathlib import Path

import numpy as np

from groupwise.config import PPO_PRESETS, RunConfig
from groupwise.envs import TARGET_TOTAL_KEY, make_env
from groupwise.reward import RewardEnsemble
from groupwise.rl.ppo import PPOAgent
from groupwise.run.checkpoint import REWARD_FILE, checkpoint_dir


def rollouts(policy_act, n, seed, ens):
    out = []
    for e in range(n):
        env = make_env("Hopper-backflip")
        o, _ = env.reset(seed=seed + e)
        obs = []
        acts = []
        rng = np.random.default_rng(e)
        for _t in range(1000):
            a = policy_act(o[None].astype(np.float32), rng)[0]
            obs.append(o)
            acts.append(a)
            o, _, term, trunc, info = env.step(a)
            if term or trunc:
                break
        r = ens.mean_reward(np.array(obs), np.array(acts))
        out.append((info[TARGET_TOTAL_KEY], r.sum(), r[:188].sum(), r[188:].sum()))
    return np.array(out)


def mk():
    return make_env("Hopper-backflip")


ref = PPOAgent(mk, PPO_PRESETS["mujoco"], 0)
ref.load(Path("/work/diag/refpol-hopper"))
for run in sys.argv[1:]:
    run = Path(run)
    cfg = RunConfig.load(run / "config.json")
    ens = RewardEnsemble.load(checkpoint_dir(run, 4) / REWARD_FILE)
    own = PPOAgent(mk, cfg.ppo, 0)
    own.load(checkpoint_dir(run, 4))
    space = mk().action_space
    res = {
        "reference": rollouts(lambda o, g: ref.act(o, g, True), 3, 100, ens),
        "own final": rollouts(lambda o, g: own.act(o, g, True), 3, 100, ens),
        "random": rollouts(
            lambda o, g: g.uniform(space.low, space.high, size=(len(o), space.shape[0])),
            3,
            100,
            ens,
        ),
    }
    for k, v in res.items():
        m = v.mean(0)
        print(
            f"{run.name:32s} {k:10s} turns {m[0]:5.2f}  learned return {m[1]:9.1f} (first 1.5 s {m[2]:8.1f}, rest {m[3]:9.1f})"
        )
