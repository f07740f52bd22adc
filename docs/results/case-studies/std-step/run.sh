#!/usr/bin/env bash
# The runs of docs/results/case-studies/std-step/ (README.md there): the best recipe with the
# learned reward standardised per step (issue 41; the default since), stand-up and backflip,
# seeds 0-4. Since the change `baseline` runs the same thing.
# Usage, from the repository root: bash docs/results/case-studies/std-step/run.sh OUT [PARALLEL]
set -euo pipefail
out=${1:?usage: run.sh OUT [PARALLEL]}; parallel=${2:-2}
python research/walker_remedies.py "$out" --seeds 0 1 2 3 4 --parallel "$parallel" \
  --targets halfcheetah-standup hopper-backflip --setups std-step
