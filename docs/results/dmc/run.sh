#!/usr/bin/env bash
# The runs of docs/results/dmc/ (README.md there): the study's dmc profile (Walker-walk and
# Cheetah-run, the three DMs, 100 preferences, SPEC's noisy teacher and a teacher never wrong)
# and PPO on the true reward at the same budget. Needs the [dmc] extra.
# Usage, from the repository root: bash docs/results/dmc/run.sh OUT [WORKERS]
# Then copy OUT/runs.csv and OUT/curves.png here and paste the printed table into README.md.
set -euo pipefail
out=${1:?usage: run.sh OUT [WORKERS]}; workers=${2:-2}
MUJOCO_GL=${MUJOCO_GL:-egl} python research/dmc_study.py "$out" --seeds 2 --workers "$workers"
