#!/usr/bin/env bash
# The three case studies at the paper's preference pairs (issue 20, README.md here): the
# teacher calibrated to people (12 % label error), PPO's MuJoCo settings, 5 rounds of STEPS
# PPO steps (default 40,000), seeds 0-4, for each DM in DMS (default: groupwise, then
# pairwise at the same comparisons) and target in TARGETS (default: all three).
# Comparisons per target are chosen so that the Groupwise-DM's pairs reach the paper's
# (--pairs paper caps them there): backflip 380 (1,032 pairs), stand-up 260 (601), splits 240 (616).
# EXTRA: further case-study options for every run (e.g. "--pretrain-steps 100000").
# SEEDS (environment): the seeds to run (default "0 1 2 3 4").
# Usage: bash docs/results/case-studies/paper-pairs/run.sh OUT_DIR [PARALLEL] [DMS] [TARGETS] [STEPS] [EXTRA]
set -euo pipefail
out=${1:?out}; parallel=${2:-2}; dms=${3:-groupwise pairwise}
targets=${4:-walker-splits halfcheetah-standup hopper-backflip}; steps=${5:-40000}; extra=${6:-}
mkdir -p "$out"
export OMP_NUM_THREADS=1 MUJOCO_GL=${MUJOCO_GL:-egl}
declare -A comparisons=([walker-splits]=240 [halfcheetah-standup]=260 [hopper-backflip]=380)
{
  for dm in $dms; do
    for s in ${SEEDS:-0 1 2 3 4}; do
      for t in $targets; do echo "$dm $t ${comparisons[$t]} $s"; done
    done
  done
} | xargs -P "$parallel" -L 1 bash -c '
  dm=$0 target=$1 comparisons=$2 seed=$3
  dir='"$out"'/$target-$dm-s$seed
  [ -f "$dir/summary.json" ] && exit 0
  mkdir "$dir.lock" 2>/dev/null || exit 0   # another invocation runs it
  trap "rmdir \"$dir.lock\"" EXIT
  rm -rf "$dir"
  groupwise case-study --target "$target" --dm "$dm" --preferences "$comparisons" \
    --pairs paper --rounds 5 --steps '"$steps"' --teacher-error 0.12 --ppo mujoco --seed "$seed" \
    '"$extra"' --out "$dir" -q > "$dir.log" 2>&1 && echo "done $dir $(date +%H:%M)" || echo "FAILED $dir"'
