#!/usr/bin/env bash
# The walker's splits with the capped step score (issue 20, README.md here): the teacher
# calibrated to people (12 % label error), 225 comparisons, 40,000 PPO steps a round.
# Groupwise-DM with the study's and with PPO's MuJoCo settings (5 rounds), the Pairwise-DM
# with the MuJoCo settings (5 rounds), and the Groupwise-DM with the MuJoCo settings over 8
# rounds (the same comparisons, more PPO), seeds as in the README.
# Usage: bash docs/results/case-studies/capped-splits/run.sh OUT_DIR [PARALLEL]
set -euo pipefail
out=${1:?out}; parallel=${2:-2}
export OMP_NUM_THREADS=1 MUJOCO_GL=${MUJOCO_GL:-egl}
{
  for s in 0 1 2 3 4; do
    echo "groupwise mujoco $s 5"; echo "groupwise study $s 5"; echo "pairwise mujoco $s 5"
  done
  for s in 0 2 4; do echo "groupwise mujoco $s 8"; done
} | xargs -P "$parallel" -L 1 bash -c '
  dm=$0 ppo=$1 seed=$2 rounds=$3
  dir='"$out"'/walker-splits-$dm-$ppo-r$rounds-s$seed
  [ -f "$dir/summary.json" ] && exit 0
  rm -rf "$dir"
  groupwise case-study --target walker-splits --dm "$dm" --preferences 225 --rounds "$rounds" \
    --steps 40000 --teacher-error 0.12 --ppo "$ppo" --no-video --seed "$seed" --out "$dir" -q \
    > "$dir.log" 2>&1 && echo "done $dir $(date +%H:%M)" || echo "FAILED $dir"'
python research/results_table.py collect "$out"
