#!/usr/bin/env bash
# The runs of docs/results/case-studies/interactive-clear/ (README.md there): the fixed Interactive-DM in the paper-pairs setup, seeds 0-4 (and 5-9 for two targets).
# Usage, from the repository root: bash docs/results/case-studies/interactive-clear/run.sh OUT [PARALLEL]
# Each run folder lands in OUT (config.json, rounds.csv, case-study.csv, summary.json,
# takeaway.json); the last line rebuilds OUT/runs.csv, the tidy table kept here.
set -euo pipefail
out=${1:?usage: run.sh OUT [PARALLEL]}; parallel=${2:-2}
engine=docs/results/case-studies/paper-pairs/run.sh   # the paper-pairs setup, seeds 0-4
bash "$engine" "$out" "$parallel" interactive-clear
SEEDS="5 6 7 8 9" bash "$engine" "$out/seeds-5-9" "$parallel" interactive-clear "halfcheetah-standup hopper-backflip"
python research/results_table.py collect "$out"
