"""A session's policy scored on its target, greedy and sampling its actions (issue 39, §7).

    python docs/results/continuous/sampled_vs_greedy.py RUN_DIR TARGET [--pretrained]
                                                        [--log-std X] [--episodes 10]

RUN_DIR is a session's run directory (or a copy `benchmarks.app_teacher --out` keeps);
`--pretrained` loads its ``checkpoints/pretrained`` (else its newest committed or mid-round
checkpoint); `--log-std` sets the policy's log σ first. Prints each way's success rate and
mean step score over the same seeded episodes.
"""

import argparse
from pathlib import Path

import numpy as np

from groupwise.config import RunConfig
from groupwise.envs import TARGETS, make_env
from groupwise.run.checkpoint import CHECKPOINTS
from groupwise.run.run import CONFIG_FILE, Run
from groupwise.study.case_studies.target_evaluation import evaluate_target
from groupwise.worker.job import PRETRAINED

parser = argparse.ArgumentParser()
parser.add_argument("run_dir", type=Path)
parser.add_argument("target", choices=sorted(TARGETS))
parser.add_argument("--pretrained", action="store_true")
parser.add_argument("--log-std", type=float)
parser.add_argument("--episodes", type=int, default=10)
args = parser.parse_args()
target = TARGETS[args.target]
with Run.create(RunConfig.load(args.run_dir / CONFIG_FILE), args.run_dir) as run:
    if args.pretrained:
        run.load_policy(args.run_dir / CHECKPOINTS / PRETRAINED)
    elif not run.restore_mid_round(run.next_round) and not run.restore():
        raise SystemExit(f"{args.run_dir} holds no checkpoint")
    if args.log_std is not None:
        run.ppo.model.policy.log_std.data.fill_(args.log_std)
    log_std = [round(float(x), 2) for x in run.ppo.model.policy.log_std.detach()]
    print(f"{run.agent.num_timesteps:,} PPO steps, log σ {log_std}")
    for deterministic in (True, False):
        evaluation = evaluate_target(
            lambda: make_env(target.env),
            run.agent.policy(deterministic),
            args.episodes,
            np.random.default_rng(0),
        )
        steps = float(np.mean([s.mean() for s in evaluation.step_scores]))
        print(
            f"{'greedy' if deterministic else 'sampled'}: success "
            f"{evaluation.success_rate(target):.0%}, mean step score {steps:.3f}"
        )
