#!/usr/bin/env bash
# The runs of docs/results/case-studies/pretrain-variants/ (README.md there): pre-training with 8 pool variants, both DMs, seeds 0-9.
# Usage, from the repository root: bash docs/results/case-studies/pretrain-variants/run.sh OUT [PARALLEL]
# Each run folder lands in OUT (config.json, rounds.csv, case-study.csv, summary.json,
# takeaway.json); the last line rebuilds OUT/runs.csv, the tidy table kept here.
set -euo pipefail
out=${1:?usage: run.sh OUT [PARALLEL]}; parallel=${2:-2}
engine=docs/results/case-studies/paper-pairs/run.sh   # the paper-pairs setup, seeds 0-4
S="walker-splits halfcheetah-standup hopper-backflip"
for seeds in "0 1 2 3 4" "5 6 7 8 9"; do
  SEEDS="$seeds" bash "$engine" "$out" "$parallel" "groupwise pairwise" "$S" 40000 "--pretrain-steps 100000 --pool-variants 8"
done
python research/results_table.py collect "$out"
