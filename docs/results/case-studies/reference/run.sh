#!/usr/bin/env bash
# The runs of docs/results/case-studies/reference/ (README.md there): PPO on each target's own
# step score (the CSVs here), and two walker case studies on the splits' old, uncapped step
# score (runs.csv: old-score-groupwise-mujoco-s1, -s4; code before ee11752, e.g. 4044402).
# Usage, from the repository root: bash docs/results/case-studies/reference/run.sh OUT [PARALLEL]
set -euo pipefail
out=${1:?usage: run.sh OUT [PARALLEL]}; parallel=${2:-2}
export OMP_NUM_THREADS=1 MUJOCO_GL=${MUJOCO_GL:-egl}
mkdir -p "$out"
for ppo in study mujoco; do   # seed 0, both PPO settings (*-study.csv, *-mujoco.csv)
  for t in walker-splits halfcheetah-standup; do echo "$t 0 $ppo"; done
done | xargs -P "$parallel" -L 1 bash -c 'python -m groupwise.study.case_studies.target_reference \
  --target $0 --seeds $1 --steps 204800 --every 40960 --ppo $2 --out '"$out"'/$0-$2'
for t in hopper-backflip walker-splits halfcheetah-standup; do   # *-mujoco-seeds-0-4.csv
  for s in 0 1 2 3 4; do echo "$t $s"; done
done | xargs -P "$parallel" -L 1 bash -c 'python -m groupwise.study.case_studies.target_reference \
  --target $0 --seeds $1 --steps 204800 --every 40960 --ppo mujoco --out '"$out"'/$0-mujoco-s$1'
# the old-score case studies (git checkout 4044402 first)
for s in 1 4; do
  groupwise case-study --target walker-splits --dm groupwise --preferences 225 --rounds 5 \
    --steps 40000 --teacher-error 0.12 --ppo mujoco --no-video --seed "$s" \
    --out "$out/cases/old-score-groupwise-mujoco-s$s" -q
done
python research/results_table.py collect "$out/cases"
