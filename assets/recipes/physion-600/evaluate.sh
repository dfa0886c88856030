#!/usr/bin/env bash
# Evaluates the finished runs of the Physion-like reproduction campaign and compares them over
# seeds:
#   assets/recipes/physion-600/evaluate.sh [test|val|hidden]      (default: test)
# test: the held-out set, 24 scenes per scenario generated apart with a seed the campaign's data
# never uses (`dynscope generate --scenario S --count 24 --seed 3`, into data/physion-test/S;
# generated here when missing) and evaluated whole (`--split all`). val: the validation split of
# the campaign's own data (data/physion-600, written by the recipes' first run), the split the
# epochs were chosen on. hidden: the paper's Physion protocol on scenes whose outcome its window
# does not show: 48 scenes per scenario, half positive, none touching the zone in the first 14
# frames (`generate --count 48 --seed 4 --hide-outcome 14 --balance`, into
# data/physion-hidden/S), evaluated whole with 14 observed frames (0.45 s) and the protocol's
# contact thresholds (1.5 x the voxel, 1.0 x in drop and contain).
# Each finished run's best-epoch checkpoint (chosen on the validation split during training) is
# evaluated once into out/campaign-physion/NAME.SPLIT.json (again only when the checkpoint is
# newer); runs still training are skipped. Then `dynscope compare` prints every variant's contact
# accuracy per scenario and end error as mean ± sd over the seeds evaluated so far, beside the
# constant-velocity floor and the contact rule on the truth, into
# out/campaign-physion/compare.SPLIT.{txt,json}.
# DYNSCOPE, DYNSCOPE_CAMPAIGN_RUNS, DYNSCOPE_CAMPAIGN_DATA and DYNSCOPE_CAMPAIGN_OUT replace the
# program (build/bin/dynscope), the checkpoints' folder (assets/runs/physion-600), the data's
# root (data) and the output folder (out/campaign-physion). DYNSCOPE_CAMPAIGN_EPOCH=last reads each
# run's last epoch instead of its best (NAME.last.SPLIT.json, compare.last.SPLIT.*).
set -euo pipefail
cd "$(dirname "$0")/../../.."
dynscope=${DYNSCOPE:-build/bin/dynscope}
source assets/recipes/progress.sh
split=${1:-test}
data_root=${DYNSCOPE_CAMPAIGN_DATA:-data}
scenarios=(drop collide roll dominoes support contain link)
protocol=()  # the evaluation protocol's options beyond the data and split
# generate_missing WHAT GENERATE_ARG ...: each scenario's scenes into $root/S, unless already there.
generate_missing() {
  local what=$1 s
  shift
  for s in "${scenarios[@]}"; do
    if [ ! -f "$root/$s/manifest.json" ]; then
      echo "generating the $what $s scenes into $root/$s"
      "$dynscope" generate --scenario "$s" "$@" --out "$root/$s" --jobs 2
    fi
  done
}
case "$split" in
  test)
    root=$data_root/physion-test
    eval_split=all
    generate_missing held-out --count 24 --seed 3
    ;;
  hidden)
    root=$data_root/physion-hidden
    eval_split=all
    generate_missing hidden-outcome --count 48 --seed 4 --hide-outcome 14 --balance
    protocol=(--observed 14 --threshold-fraction 1.5 --scenario-threshold-fraction drop=1
      --scenario-threshold-fraction contain=1)
    ;;
  val)
    root=$data_root/physion-600
    eval_split=val
    for s in "${scenarios[@]}"; do
      if [ ! -f "$root/$s/manifest.json" ]; then
        echo "$root/$s is missing: a campaign recipe's first run writes it" \
          "(assets/recipes/run.sh assets/recipes/physion-600/centred_s1.json)" >&2
        exit 1
      fi
    done
    ;;
  -h | --help)
    sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'
    exit 0
    ;;
  *)
    echo "usage: $0 [test|val|hidden]  (--help explains)" >&2
    exit 2
    ;;
esac
data=()
for s in "${scenarios[@]}"; do data+=(--data "$root/$s"); done
# The shipped recipe's three seeds, the paper's architecture, the static-bodies-held variant, the
# level-0 radius of 0.15 and the 60-epoch schedule: one group, so its evaluations and its comparison
# share one folder (the files' SPLIT keeps the three data sets apart).
out=${DYNSCOPE_CAMPAIGN_OUT:-out/campaign-physion}
evaluate_and_compare assets/recipes/physion-600 "${DYNSCOPE_CAMPAIGN_RUNS:-assets/runs/physion-600}" \
  "$out" "$out" "$split" "centred paper held radius15 long60" \
  "${data[@]}" --split "$eval_split" "${protocol[@]}"
