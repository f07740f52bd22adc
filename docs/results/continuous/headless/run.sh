#!/usr/bin/env bash
# Issue 39, deliverable 4: the 5-seed table at 10 and 20 minutes of the calibrated teacher's
# time, on the headless continuous round's virtual clock (the app's mechanism: pools cut from
# PPO's latest rollouts before each round's end, `run.continuous.cut_next`). The app's
# settings: recipe `teach`, 100 behaviours a pool, 20 minutes of comparisons at the paper's
# pace for the target (`run.continuous.paper_pace`) in an even number of rounds of about 20
# (the app's default), so that the middle round ends at about 10 minutes: the stand-up 127
# comparisons at 9.469 s in 6 rounds of 21-22, the backflip 224 at 5.357 s in 12 rounds of
# 18-19; the teacher wrong on 12 % of unequal pairs; PPO at 1,300 steps a second of
# the teacher's time (rate.json: what each of two app sessions side by side got on this 2-core
# machine, docs/results/continuous/app-budget), against rounds mode with the app's 20,000 PPO
# steps after each round (the teacher waits for them on the clock).
# Usage, from the repository root: bash docs/results/continuous/headless/run.sh OUT [PARALLEL]
# (CELLS="halfcheetah-standup:continuous:0 ..." runs only those; a finished cell is kept)
# then: python -m groupwise.study.case_studies.continuous_table OUT/*/ --marks 10 20
# rounds.csv holds every finished run's rounds (score, success, pool, ties; `variant`: the
# code it ran, "default (kept policy)" since the kept policy, run/kept_policy.py), appended
# with: python -m groupwise.study.case_studies.continuous_table OUT/*/ --append-to rounds.csv
# --variant NAME, and read back with: ... continuous_table --table rounds.csv --marks 10 20;
# the run folders themselves are artifacts, not kept. decisions.csv: the kept policy's
# decisions, from the cells' logs: python decisions.py OUT/*.log (VARIANT=NAME).
set -euo pipefail
out=${1:?usage: run.sh OUT [PARALLEL]}; parallel=${2:-2}
here=$(cd "$(dirname "$0")" && pwd)
export OMP_NUM_THREADS=1 MUJOCO_GL=${MUJOCO_GL:-egl}
mkdir -p "$out"
default=""
for seed in 0 1 2 3 4; do
  for target in halfcheetah-standup hopper-backflip; do
    for mode in continuous rounds; do default+="$target:$mode:$seed "; done
  done
done
printf '%s\n' ${CELLS:-$default} | xargs -P "$parallel" -L 1 bash -c '
  IFS=: read -r target mode seed <<< "$0"
  dir='"$out"'/$target-$mode-s$seed
  [ -f "$dir/summary.json" ] && exit 0
  mkdir -p "$dir"
  read -r pace comparisons rounds < <(python -c "
from groupwise.run.continuous import paper_pace
pace = paper_pace(\"$target\", pairwise=False)
comparisons = round(1200 / pace)
rounds = 2 * max(1, round(comparisons / 40))
print(pace, comparisons, rounds)")
  # rate.json, and rounds of equal size (round 0 too, as in the app)
  python -c "import json, sys; c = json.load(open(sys.argv[1]))
c[\"loop\"] = {\"initial_fraction\": 1 / $rounds}; json.dump(c, open(sys.argv[2], \"w\"))" \
    '"$here"'/rate.json "$dir/research.json"
  groupwise case-study --target "$target" --training "$mode" --preferences "$comparisons" \
    --rounds "$rounds" --steps 20000 --pool-size 100 --teacher-error 0.12 \
    --teacher-pace "$pace" --eval-episodes 5 \
    --no-video --seed "$seed" --config "$dir/research.json" --out "$dir" -q > "$dir.log" 2>&1 \
    && echo "done $dir" || echo "FAILED $dir"'
