#!/usr/bin/env bash
# The Groupwise-DM part of issue 20's case studies (README.md here): a teacher calibrated to
# people (12 % label error), comparisons chosen to stay near the paper's preference pairs
# (hopper 1,032, cheetah 601, walker 616), 5 rounds x 40,000 PPO steps, seeds 0-4.
# Usage: bash docs/results/case-studies/calibrated/run.sh OUT_DIR [PARALLEL]
set -euo pipefail
out=${1:?out}; parallel=${2:-2}
export OMP_NUM_THREADS=1 MUJOCO_GL=${MUJOCO_GL:-egl}
cells=()
for seed in 0 1 2 3 4; do
  for row in "hopper-backflip 290" "halfcheetah-standup 220" "walker-splits 225"; do
    read -r target comparisons <<<"$row"
    cells+=("$target $comparisons $seed")
  done
done
printf '%s\n' "${cells[@]}" | xargs -P "$parallel" -L 1 bash -c '
  target=$0 comparisons=$1 seed=$2
  dir='"$out"'/$target-groupwise-s$seed
  [ -f "$dir/summary.json" ] && exit 0
  rm -rf "$dir"
  groupwise case-study --target "$target" --dm groupwise --preferences "$comparisons" \
    --rounds 5 --steps 40000 --teacher-error 0.12 --no-video --seed "$seed" --out "$dir" -q \
    > "$dir.log" 2>&1 && echo "done $dir $(date +%H:%M)" || echo "FAILED $dir"'
python research/results_table.py collect "$out"
