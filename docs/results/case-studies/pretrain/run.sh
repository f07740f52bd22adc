#!/usr/bin/env bash
# The runs of docs/results/case-studies/pretrain/ (README.md there): 100,000 steps of state-entropy pre-training: the backflip (both DMs, seeds 0-9) and the splits (Groupwise-DM, seeds 0-4).
# Usage, from the repository root: bash docs/results/case-studies/pretrain/run.sh OUT [PARALLEL]
# Each run folder lands in OUT (config.json, rounds.csv, case-study.csv, summary.json,
# takeaway.json); the last line rebuilds OUT/runs.csv, the tidy table kept here.
set -euo pipefail
out=${1:?usage: run.sh OUT [PARALLEL]}; parallel=${2:-2}
engine=docs/results/case-studies/paper-pairs/run.sh   # the paper-pairs setup, seeds 0-4
for seeds in "0 1 2 3 4" "5 6 7 8 9"; do
  SEEDS="$seeds" bash "$engine" "$out" "$parallel" "groupwise pairwise" hopper-backflip 40000 "--pretrain-steps 100000"
done
bash "$engine" "$out" "$parallel" groupwise walker-splits 40000 "--pretrain-steps 100000"
python research/results_table.py collect "$out"
