#!/usr/bin/env bash
# The runs of docs/results/case-studies/dm-comparison/ (../README.md, "Groupwise-DM vs
# Pairwise-DM on the three targets"): 400 comparisons, 5 rounds, SPEC §7's sigma = 0.25
# teacher, the study's PPO, seeds 0-2. Ran on the code of 2026-11-30 (commit 95e7586's day).
# Usage, from the repository root: bash docs/results/case-studies/dm-comparison/run.sh OUT [PARALLEL]
set -euo pipefail
out=${1:?usage: run.sh OUT [PARALLEL]}; parallel=${2:-2}
export OMP_NUM_THREADS=1 MUJOCO_GL=${MUJOCO_GL:-egl}
for t in hopper:hopper-backflip cheetah:halfcheetah-standup walker:walker-splits; do
  for dm in groupwise pairwise; do
    for seed in 0 1 2; do echo "${t%%:*} ${t#*:} $dm $seed"; done
  done
done | xargs -P "$parallel" -L 1 bash -c '
  name=$0 target=$1 dm=$2 seed=$3
  groupwise case-study --target "$target" --dm "$dm" --preferences 400 --rounds 5 \
    --steps 40000 --seed "$seed" --out '"$out"'/$name-$dm-s$seed -q'
python research/results_table.py collect "$out"
