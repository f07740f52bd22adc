#!/usr/bin/env bash
# Issue 39, deliverable 3, through the app's own path: the stand-up in continuous mode with
# one of the case study's settings in the app's session (`--research`, recorded per cell),
# two live sessions side by side on the 2-core machine (as the app table's seeds 1-2 ran).
# Arms (the default is docs/results/continuous/app/cells.jsonl):
#   obs        the reward over the observation alone, no learned control cost
#   explore    5 % random actions in the sampled part of a pool, not the app's 25 %
#   case       both: the case study's settings
# Usage, from the repository root: bash docs/results/continuous/app-ablation/run.sh OUT ARM "SEEDS"
# then: python -m benchmarks.app_teacher --summary OUT/*/cells.jsonl
set -euo pipefail
out=${1:?usage: run.sh OUT ARM SEEDS}; arm=${2:?ARM: obs, explore or case}; seeds=${3:-"0 1"}
case $arm in
  obs) research='{"reward": {"use_actions": false}}' ;;
  explore) research='{"loop": {"exploration_fraction": 0.05}}' ;;
  case) research='{"reward": {"use_actions": false}, "loop": {"exploration_fraction": 0.05}}' ;;
  *) echo "unknown arm $arm: obs, explore or case" >&2; exit 2 ;;
esac
mkdir -p "$out"
for seed in $seeds; do
  python -m benchmarks.app_teacher --targets halfcheetah-standup --seeds "$seed" \
    --minutes 2.5 5 7.5 10 --training continuous --research "$research" \
    --out "$out/$arm-s$seed" --log "$out/$arm-s$seed.log" > "$out/$arm-s$seed.table" &
done
wait
