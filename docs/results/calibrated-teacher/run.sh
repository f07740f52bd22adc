#!/usr/bin/env bash
# The runs of docs/results/calibrated-teacher/ (README.md there): the backflip taught by a
# teacher wrong as often as the paper's people (12 %), both DMs, seed 0.
# Usage, from the repository root: bash docs/results/calibrated-teacher/run.sh OUT
set -euo pipefail
out=${1:?usage: run.sh OUT}
for dm in groupwise pairwise; do
  groupwise case-study --target hopper-backflip --dm "$dm" --preferences 400 --rounds 5 \
    --steps 40000 --seed 0 --teacher-error 0.12 --no-video --out "$out/$dm"
done
python research/results_table.py collect "$out"
