#!/usr/bin/env bash
# The run of docs/results/case-studies/hopper-backflip/ (../README.md, "Earlier runs"): the
# first backflip, 400 comparisons, SPEC §7's sigma = 0.25 teacher, seed 0 (683 s on 2 cores).
# Usage, from the repository root: bash docs/results/case-studies/hopper-backflip/run.sh OUT
set -euo pipefail
out=${1:?usage: run.sh OUT}
groupwise case-study --target hopper-backflip --dm groupwise --preferences 400 --rounds 5 \
  --steps 40000 --seed 0 --out "$out"
python research/results_table.py collect "$out"
