#!/usr/bin/env bash
# The runs of docs/results/case-studies/circle/ (README.md there): the paper-pairs setup with the root's pitch on the circle, Groupwise-DM, seeds 0-4.
# Usage, from the repository root: bash docs/results/case-studies/circle/run.sh OUT [PARALLEL]
# Each run folder lands in OUT (config.json, rounds.csv, case-study.csv, summary.json,
# takeaway.json); the last line rebuilds OUT/runs.csv, the tidy table kept here.
# Code: commit ffb2083 (PitchOnCircle, reverted since: git checkout ffb2083 first).
set -euo pipefail
out=${1:?usage: run.sh OUT [PARALLEL]}; parallel=${2:-2}
engine=docs/results/case-studies/paper-pairs/run.sh   # the paper-pairs setup, seeds 0-4
bash "$engine" "$out" "$parallel" groupwise "hopper-backflip walker-splits halfcheetah-standup" 40000
python research/results_table.py collect "$out"
