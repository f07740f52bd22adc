#!/usr/bin/env bash
# The runs of docs/results/case-studies/bonus/ (README.md there): the paper-pairs setup with RUNE's reward bonus, Groupwise-DM, seeds 0-4.
# Usage, from the repository root: bash docs/results/case-studies/bonus/run.sh OUT [PARALLEL]
# Each run folder lands in OUT (config.json, rounds.csv, case-study.csv, summary.json,
# takeaway.json); the last line rebuilds OUT/runs.csv, the tidy table kept here.
# Code: commit 697627f (issue 38 takes --reward-bonus out of the CLI: check out 697627f to rerun).
set -euo pipefail
out=${1:?usage: run.sh OUT [PARALLEL]}; parallel=${2:-2}
engine=docs/results/case-studies/paper-pairs/run.sh   # the paper-pairs setup, seeds 0-4
bash "$engine" "$out" "$parallel" groupwise "hopper-backflip walker-splits halfcheetah-standup" 40000 "--reward-bonus 1"
python research/results_table.py collect "$out"
