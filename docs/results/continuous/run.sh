#!/usr/bin/env bash
# The continuous-vs-rounds table (README.md here): 3 targets x 2 modes x 3 seeds, a
# calibrated teacher (12 % label error) at the paper's pace for 5 minutes of its time.
# Usage: bash docs/results/continuous/run.sh OUT_DIR [PARALLEL]
set -euo pipefail
out=${1:?output directory}
parallel=${2:-2}
export OMP_NUM_THREADS=1 MUJOCO_GL=${MUJOCO_GL:-egl}
cells=()
# target, comparisons in 5 minutes at the paper's pace (groupwise DM), that pace in s
for row in "hopper-backflip 56 5.357" "halfcheetah-standup 32 9.469" "walker-splits 28 10.558"; do
  read -r target comparisons pace <<<"$row"
  for seed in 0 1 2; do
    for mode in continuous rounds; do
      cells+=("$target $comparisons $pace $mode $seed")
    done
  done
done
printf '%s\n' "${cells[@]}" | xargs -P "$parallel" -L 1 bash -c '
  target=$0 comparisons=$1 pace=$2 mode=$3 seed=$4
  dir='"$out"'/$target-$mode-s$seed
  [ -f "$dir/summary.json" ] && exit 0
  groupwise case-study --target "$target" --dm groupwise --preferences "$comparisons" \
    --rounds 3 --steps 40000 --training "$mode" --teacher-error 0.12 \
    --teacher-pace "$pace" --no-video --seed "$seed" --out "$dir" -q \
    > "$dir.log" 2>&1 && echo "done $dir" || echo "FAILED $dir"'
