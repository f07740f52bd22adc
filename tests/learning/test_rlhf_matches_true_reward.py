"""RLHF from near-noise-free labels learns what PPO on the true reward learns (marker `slow`).

On a standard Gymnasium env with a fixed horizon and a dense reward (Pendulum-v1, 200
steps), the loop with the pairwise decision-maker and nearly noise-free labels (σ = 0.05 per
step, so a fragment's noise sd is 1.25 against fragment returns that differ by tens to
hundreds) must reach at least 80 % of what PPO on the true reward reaches with the same
steps, both normalised from a random policy, over 3 seeds; and no seed may collapse after
its peak, the failure the peer benchmark against imitation showed (benchmarks/peer.py): each
seed's last round may fall below its best round by at most COLLAPSE = a fifth of the gap
between random and true-reward PPO (about 1,000 here).

That bound was the spread of the final returns over seeds (plus 5 % of the gap), but a seed
that collapses widens that spread, so the bound loosened exactly when it was needed: with
the earlier measurement below the spread was 64 % of the gap. A fixed fifth keeps what the spread
meant for seeds that learn: their spread (13 % of the gap for the two that learned below;
2 % and 20 % for 3 and 5 seeds in docs/results/peer/README.md) plus the 5 % margin. It is
far above the drops the peer benchmark saw on Pendulum-v1 (last vs best round, mean over
seeds: 10–12 for the default loop, up to 152 for the weakest variants) and far below a fall
back towards random.

Measured 2026-12-02 (issue 20), random −1,205, true-reward PPO −188 / −127 / −163: RLHF
−252 / −121 / −165, 98 % of the gap, no seed below its best round. Before, with one reward
MLP over [obs ; act] (`RewardConfig.action_term="joint"`): −260 / −1,491 / −445, 45 % (seed 1
learned to spin); such a reward pays torque for the states it leads to within a fragment
(at SPEC noise, braking near the top, which PPO then did everywhere: docs/results/peer). The
default control-cost action term cannot pay an action.
"""

import numpy as np
import pytest

from groupwise.config import LoopConfig, PPOConfig, RunConfig, TeacherConfig
from groupwise.envs import make_env
from groupwise.rl.policy import RandomPolicy
from groupwise.rl.ppo import PPOAgent
from groupwise.rl.rollout import evaluate
from groupwise.run.headless import run_session
from groupwise.run.streams import eval_rng

ENV = "Pendulum-v1"
SEEDS = (0, 1, 2)
STEPS = 102_400
EPISODES = 10
GOAL = 0.8
"""Share of the random-to-true-reward-PPO gap the loop must close (measured: 98 %)."""
COLLAPSE = 0.2
"""Share of that gap a seed's last round may lose from its best round (module docstring)."""


def _loop(seed: int) -> LoopConfig:
    return LoopConfig(
        env=ENV,
        decision_maker="pairwise",
        comparisons=200,
        rounds=5,
        steps=STEPS,
        fragment_length=25,
        eval_episodes=EPISODES,
        seed=seed,
    )


@pytest.mark.slow
def test_rlhf_closes_the_gap_to_true_reward_ppo_without_collapse(tmp_path):
    def make():
        return make_env(ENV)

    random = np.mean(
        [
            evaluate(make, RandomPolicy(make().action_space), EPISODES, eval_rng(s)).mean()
            for s in SEEDS
        ]
    )
    true_ppo, rlhf, drops = [], [], []
    for seed in SEEDS:
        agent = PPOAgent(make, PPOConfig(tensorboard=False), seed=seed)
        agent.learn(STEPS, seed=seed)
        policy = agent.policy(deterministic=True)
        true_ppo.append(evaluate(make, policy, EPISODES, eval_rng(seed)).mean())
        agent.close()
        cfg = RunConfig(
            loop=_loop(seed),
            teacher=TeacherConfig(noise_sigma=0.05),
            ppo=PPOConfig(tensorboard=False),
        )
        records = run_session(cfg, tmp_path / f"seed-{seed}", show_progress=False)
        curve = [r.true_return_mean for r in records]
        rlhf.append(curve[-1])
        drops.append(max(curve) - curve[-1])
    print(
        f"{ENV}: random {random:.1f}, true-reward PPO {np.round(true_ppo, 1)}, "
        f"RLHF {np.round(rlhf, 1)}, last-round drops {np.round(drops, 1)}"
    )
    gap = np.mean(true_ppo) - random
    assert gap > 0, "PPO on the true reward did not learn: the comparison is meaningless"
    share = (np.mean(rlhf) - random) / gap
    assert share >= GOAL, f"RLHF closed {share:.0%} of the gap to true-reward PPO, not 80 %"
    collapsed = [seed for seed, drop in zip(SEEDS, drops, strict=True) if drop > COLLAPSE * gap]
    assert not collapsed, f"seeds {collapsed} fell by more than {COLLAPSE:.0%} of the gap"
