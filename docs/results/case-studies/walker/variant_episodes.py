"""A walker round's policy against its pool variants: who does the splits, who is paid for it.

    python docs/results/case-studies/walker/variant_episodes.py RUN_DIR ROUND [--episodes 2]

For round ROUND of a `groupwise case-study --target walker-splits` run (with
`--pool-variants`): the policy that sampled the round's pool (checkpoint ROUND − 1) and the
round's biased variants of it, drawn again from the round's sample stream as `begin_round`
drew them, each play greedy episodes from the same reset seeds. One Markdown row each: the
longest split held (s), the sum of the splits' step scores (what the simulated teacher
perceives), and the return under the reward ensemble fitted after the round (checkpoint
ROUND: what PPO then trains on).
"""

import argparse
import json
from pathlib import Path

import numpy as np

from groupwise.envs import make_env
from groupwise.reward.ensemble import RewardEnsemble
from groupwise.rl.policy import biased_variants
from groupwise.rl.policy_files import load_policy
from groupwise.rl.rollout import sample_trajectories
from groupwise.run.checkpoint import REWARD_FILE, checkpoint_dir
from groupwise.run.streams import round_streams


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path)
    parser.add_argument("round", type=int, help="a round >= 1 of the run")
    parser.add_argument("--episodes", type=int, default=2)
    args = parser.parse_args()
    loop = json.loads((args.run / "config.json").read_text())["loop"]
    env = loop["env"]

    def make():
        return make_env(env)

    greedy = load_policy(str(checkpoint_dir(args.run, args.round - 1)), env, deterministic=True)
    probe = make()
    space = probe.action_space
    probe.close()
    stream = round_streams(loop["seed"], args.round).sample
    variants = biased_variants(
        greedy, space, loop["pool_variants"], loop["pool_variant_scale"], stream
    )
    reward = RewardEnsemble.load(checkpoint_dir(args.run, args.round) / REWARD_FILE)
    print(f"{args.run.name}, round {args.round}, {args.episodes} greedy episodes each\n")
    print("| policy | split held, s | step-score sum | learned return |")
    print("|---|---|---:|---:|")
    for name, policy in [("the round's policy", greedy)] + [
        (f"variant {k}", v) for k, v in enumerate(variants, start=1)
    ]:
        episodes = sample_trajectories(make, policy, args.episodes, np.random.default_rng(7))
        held = ", ".join(f"{e.episode_score:.2f}" for e in episodes)
        score = np.mean([e.true_rewards.sum() for e in episodes])
        learned = np.mean([reward.returns(e.obs[None], e.acts[None]).mean() for e in episodes])
        print(f"| {name} | {held} | {score:,.0f} | {learned:.1f} |")


if __name__ == "__main__":
    main()
