#!/usr/bin/env bash
# The runs of docs/results/case-studies/remedies/ (README.md there): issue 41's remedies on the
# walker's splits, each on the best recipe, seeds 0-4 (then 5-9 to confirm). The remedies
# left the code: run this file at commit 2710cd9 (coverage, reset, all) or 5fed786 (surf),
# with their names in --setups; here it runs the best recipe with the diagnostic.
# Usage, from the repository root: bash docs/results/case-studies/remedies/run.sh OUT [PARALLEL]
# Each run folder lands in OUT/<setup>/walker-splits-groupwise-s<seed>; the runner then
# rebuilds OUT/runs.csv, the tidy table kept here, and prints the summary table.
set -euo pipefail
out=${1:?usage: run.sh OUT [PARALLEL]}; parallel=${2:-2}
python research/walker_remedies.py "$out" --seeds 0 1 2 3 4 --parallel "$parallel" \
  --setups baseline
