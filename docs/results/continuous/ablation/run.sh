#!/usr/bin/env bash
# Issue 39, deliverable 3: why continuous loses the stand-up in the app. The headless
# continuous round (the app's mechanism on a virtual clock, PPO 3,000 steps a second of the
# teacher's time) for 10 minutes of a calibrated teacher at the paper's pace: 63 comparisons,
# one pool of 100, recipe `teach`. One change a arm against the case study's defaults:
#   per-step       the defaults (the learned reward standardised per step for PPO)
#   return-scale   PPO's reward return-scaled by VecNormalize instead (return-scale.json)
#   obs-act        the reward over observation and action, a learned control cost: the
#                  app's default reward inputs (obs-act.json)
#   two-pools      two rounds of the 63 comparisons, 44 then 19 (two-pools.json), so a fresh
#                  pool of the policy opens at 7 minutes, as the app's round 1 did (rounds of 44)
#   explore        25 % random actions in the sampled part of a pool: the app's default (explore.json)
#   rate           PPO at 2,100 steps a second of the teacher's time, the app's rate on this
#                  2-core machine (1.0-1.4 M steps in 10 minutes), not one free core's 3,000 (rate.json)
# Usage, from the repository root: bash docs/results/continuous/ablation/run.sh OUT [PARALLEL]
# (ARMS="obs-act rate" runs only those arms; cells run seed by seed, and a finished cell is kept)
# then: python -m groupwise.study.case_studies.continuous_table OUT/*/
set -euo pipefail
out=${1:?usage: run.sh OUT [PARALLEL]}; parallel=${2:-2}
here=$(cd "$(dirname "$0")" && pwd)
export OMP_NUM_THREADS=1 MUJOCO_GL=${MUJOCO_GL:-egl}
mkdir -p "$out"
cells=()
for seed in 0 1 2; do
  for arm in ${ARMS:-per-step return-scale obs-act two-pools rate explore}; do
    cells+=("$arm $seed")
  done
done
printf '%s\n' "${cells[@]}" | xargs -P "$parallel" -L 1 bash -c '
  arm=$0 seed=$1
  dir='"$out"'/$arm-s$seed
  [ -f "$dir/summary.json" ] && exit 0
  config=(); [ -f '"$here"'/$arm.json ] && config=(--config '"$here"'/$arm.json)
  rounds=1; [ "$arm" = two-pools ] && rounds=2
  groupwise case-study --target halfcheetah-standup --training continuous --preferences 63 \
    --rounds "$rounds" --pool-size 100 --teacher-error 0.12 --teacher-pace 9.469 --no-video \
    --seed "$seed" --out "$dir" "${config[@]}" -q > "$dir.log" 2>&1 \
    && echo "done $dir" || echo "FAILED $dir"'
