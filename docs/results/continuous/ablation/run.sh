#!/usr/bin/env bash
# Issue 39, deliverable 3: why continuous loses the stand-up. The headless continuous round
# (the app's mechanism on a virtual clock) for 10 minutes of a calibrated teacher at the
# paper's pace, 5 seeds, the default (the learned reward standardised per step) against the
# return-scaled reward (config `return-scale.json`), and rounds mode at the default beside.
# Usage, from the repository root: bash docs/results/continuous/ablation/run.sh OUT [PARALLEL]
set -euo pipefail
out=${1:?usage: run.sh OUT [PARALLEL]}; parallel=${2:-2}
here=$(cd "$(dirname "$0")" && pwd)
export OMP_NUM_THREADS=1 MUJOCO_GL=${MUJOCO_GL:-egl}
mkdir -p "$out"
cells=()
for seed in 0 1 2 3 4; do
  cells+=("continuous std-step $seed" "continuous return-scale $seed")
done
for seed in 0 1 2 3 4; do cells+=("rounds std-step $seed"); done
printf '%s\n' "${cells[@]}" | xargs -P "$parallel" -L 1 bash -c '
  mode=$0 reward=$1 seed=$2
  dir='"$out"'/$mode-$reward-s$seed
  [ -f "$dir/summary.json" ] && exit 0
  config=(); [ "$reward" = return-scale ] && config=(--config '"$here"'/return-scale.json)
  groupwise case-study --target halfcheetah-standup --training "$mode" --preferences 63 \
    --rounds 1 --pool-size 100 --teacher-error 0.12 --teacher-pace 9.469 --no-video \
    --seed "$seed" --out "$dir" "${config[@]}" -q > "$dir.log" 2>&1 \
    && echo "done $dir" || echo "FAILED $dir"'
