#!/usr/bin/env bash
# The app-path table of docs/results/continuous/README.md (issue 39): a simulated person
# teaching through a live groupwise serve, one session at a time, continuous and rounds.
# Usage, from the repository root: bash docs/results/continuous/app/run.sh OUT [SEEDS]
set -euo pipefail
out=${1:?usage: run.sh OUT [SEEDS]}; seeds=${2:-0}
for seed in $seeds; do
  for target in halfcheetah-standup hopper-backflip walker-splits; do
    for training in continuous rounds; do
      cell=$out/$target-$seed-$training
      python -m benchmarks.app_teacher --targets "$target" --seeds "$seed" \
        --minutes 2.5 5 7.5 10 --training "$training" --out "$cell" --log "$cell.log" \
        > "$cell.table"
    done
  done
done
