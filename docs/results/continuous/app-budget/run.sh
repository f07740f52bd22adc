#!/usr/bin/env bash
# Issue 39 through the app's own path with the default recipe (teach: the reward over the
# observation, 5 % random actions): the stand-up continuous at the app's own round length
# (the New-session default, 20 comparisons a round) against rounds mode at 20 and at the
# paper's 44, the splits continuous and the backflip in both modes at 20; two live sessions
# side by side on the 2 cores. (The experiment of commit 8aace11, PPO from round 1: the two
# stand-up cells in cells.jsonl with research ppo_from_round, run at that commit with
# --research '{"training": {"ppo_from_round": 1}}'.)
# Usage, from the repository root: bash docs/results/continuous/app-budget/run.sh OUT
# then: python -m benchmarks.app_teacher --summary OUT/*/cells.jsonl
set -euo pipefail
out=${1:?usage: run.sh OUT}
mkdir -p "$out"
cell() {  # TARGET TRAINING SEED [COMPARISONS]
  local name=$1-$2${4:+-c$4}-s$3
  python -m benchmarks.app_teacher --targets "$1" --seeds "$3" ${4:+--comparisons "$4"} \
    --minutes 2.5 5 7.5 10 --training "$2" --out "$out/$name" --log "$out/$name.log" \
    > "$out/$name.table"
}
export -f cell; export out
{
  for seed in 0 1 2 3 4; do echo "halfcheetah-standup continuous $seed 20"; done
  for seed in 0 1 2 3 4; do echo "halfcheetah-standup rounds $seed 20"; done
  for seed in 0 1 2; do echo "halfcheetah-standup rounds $seed"; done
  for seed in 1 2; do echo "walker-splits continuous $seed"; done
  for seed in 0 1 2 3 4; do echo "hopper-backflip continuous $seed 20"; done
  for seed in 0 1 2 3 4; do echo "hopper-backflip rounds $seed 20"; done
} | xargs -P 2 -L 1 bash -c 'cell "$@"' _
