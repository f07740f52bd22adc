#!/usr/bin/env bash
# The runs of docs/results/case-studies/walker/ (README.md there): every splits setup, one
# subfolder each, Groupwise-DM unless said.
# Usage, from the repository root: bash docs/results/case-studies/walker/run.sh OUT [PARALLEL]
# Each run folder lands in OUT (config.json, rounds.csv, case-study.csv, summary.json,
# takeaway.json); the last line rebuilds OUT/runs.csv, the tidy table kept here.
# Code: observed/ and observed-pretrain/ ran on commit e32adb8 (the feet's heights observed,
# reverted since). keep/, adopt/, adopt-any/, greedy/, greedy-adopt/, pessimism/ and
# lookahead/ use options of commit 697627f that issue 38 takes out of the CLI: check out
# 697627f to rerun them (adopt-any/ ran an earlier adoption rule than that commit's).
set -euo pipefail
out=${1:?usage: run.sh OUT [PARALLEL]}; parallel=${2:-2}
engine=docs/results/case-studies/paper-pairs/run.sh   # the paper-pairs setup, seeds 0-4
S="--pretrain-steps 100000 --pool-variants 8"
w() {  # w SETUP DMS STEPS EXTRA [SEEDS]: one setup into OUT/SETUP
  SEEDS=${5:-0 1 2 3 4} bash "$engine" "$out/$1" "$parallel" "$2" walker-splits "$3" "$4"
}
for seeds in "0 1 2 3 4" "5 6 7 8 9"; do
  w pretrain-variants groupwise 40000 "$S" "$seeds"
  w everything groupwise 40000 "$S --pool-size 500" "$seeds"
  w greedy groupwise 40000 "$S --pool-variants-greedy" "$seeds"
  w pairs-2x groupwise 40000 "$S --preferences 480 --pairs 1232" "$seeds"
done
w everything pairwise 40000 "$S --pool-size 500"
w observed groupwise 40000 ""                       # at e32adb8
w observed-pretrain groupwise 40000 "--pretrain-steps 100000"   # at e32adb8
w pool-500 groupwise 40000 "--pool-size 500"
w behaviours-0.5s groupwise 40000 "--seconds 0.5"
w ppo-100k groupwise 100000 "$S"
w keep groupwise 40000 "$S --continue-from preferred"
w adopt groupwise 40000 "$S --adopt-variants"
w adopt-any groupwise 40000 "$S --adopt-variants"   # the first adoption rule (above ½ over >= 4 pairs)
w greedy-adopt groupwise 40000 "$S --pool-variants-greedy --adopt-variants"
w pessimism groupwise 40000 "$S --reward-pessimism 1"
w lookahead groupwise 40000 "$S --pool-lookahead 40960"
python research/results_table.py collect "$out"
