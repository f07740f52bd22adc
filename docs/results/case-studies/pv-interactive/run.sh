#!/usr/bin/env bash
# The runs of docs/results/case-studies/pv-interactive/ (README.md there): the Interactive-DM with pre-training and 8 pool variants, seeds 0-4.
# Usage, from the repository root: bash docs/results/case-studies/pv-interactive/run.sh OUT [PARALLEL]
# Each run folder lands in OUT (config.json, rounds.csv, case-study.csv, summary.json,
# takeaway.json); the last line rebuilds OUT/runs.csv, the tidy table kept here.
set -euo pipefail
out=${1:?usage: run.sh OUT [PARALLEL]}; parallel=${2:-2}
engine=docs/results/case-studies/paper-pairs/run.sh   # the paper-pairs setup, seeds 0-4
bash "$engine" "$out" "$parallel" interactive-clear "walker-splits hopper-backflip halfcheetah-standup" 40000 \
    "--pretrain-steps 100000 --pool-variants 8"
python research/results_table.py collect "$out"
