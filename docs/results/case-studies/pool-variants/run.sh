#!/usr/bin/env bash
# The runs of docs/results/case-studies/pool-variants/ (README.md there): 8 pool variants, both DMs, seeds 0-9 (the baseline's seeds 5-9 are ../paper-pairs/run.sh's).
# Usage, from the repository root: bash docs/results/case-studies/pool-variants/run.sh OUT [PARALLEL]
# Each run folder lands in OUT (config.json, rounds.csv, case-study.csv, summary.json,
# takeaway.json); the last line rebuilds OUT/runs.csv, the tidy table kept here.
set -euo pipefail
out=${1:?usage: run.sh OUT [PARALLEL]}; parallel=${2:-2}
engine=docs/results/case-studies/paper-pairs/run.sh   # the paper-pairs setup, seeds 0-4
S="walker-splits halfcheetah-standup hopper-backflip"
bash "$engine" "$out" "$parallel" "groupwise pairwise" "$S" 40000 "--pool-variants 8"
SEEDS="5 6 7 8 9" bash "$engine" "$out" "$parallel" "groupwise pairwise" "$S" 40000 "--pool-variants 8"
python research/results_table.py collect "$out"
