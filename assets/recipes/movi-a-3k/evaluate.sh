#!/usr/bin/env bash
# Evaluates the finished runs of the movi-a reproduction campaign on its test (or validation) split
# and compares them over seeds:
#   assets/recipes/movi-a-3k/evaluate.sh [val|test] [best|last]      (defaults: test, best)
# Each finished run's best-epoch checkpoint (chosen on the validation split during training) is
# evaluated once into out/campaign-evals/DATA/NAME.SPLIT.json (DATA: movi-a-3k, or movi-a-3k-sparse
# for the sparse-mesh runs; again only when the checkpoint is newer), however many groups below
# compare it; with `last`, its last epoch's checkpoint instead, into NAME.last.SPLIT.json and
# compare.last.SPLIT.* (the same runs without the epoch choice, to see which claims depend on it);
# runs still training are skipped. Then `dynscope compare` prints every variant's end error as
# mean ± sd over the seeds evaluated so far, and the paired per-scene comparisons behind the paper's
# claims, for each group of runs into its own folder: the first budget's runs into
# out/campaign/compare.SPLIT.{txt,json}; the runs at the paper's size (C = 32, 4 levels: the
# *_c32l4_sN recipes) into out/campaign-c32l4/; the mesh runs on sparse meshes
# (data/movi-a-3k-sparse: the same scenes, boxes and cylinders stored with the fewest vertices) into
# out/campaign-sparse/; the runs trained on their own one-step predictions (the *_pf1 recipes)
# beside the same runs trained without it into out/campaign-pf1/.
# DYNSCOPE, DYNSCOPE_CAMPAIGN_RUNS and DYNSCOPE_CAMPAIGN_OUT replace the program
# (build/bin/dynscope), the checkpoints' folder (assets/runs/movi-a-3k) and the folder the
# evaluations and comparisons go under (out).
set -euo pipefail
cd "$(dirname "$0")/../../.."
dynscope=${DYNSCOPE:-build/bin/dynscope}
runs=${DYNSCOPE_CAMPAIGN_RUNS:-assets/runs/movi-a-3k}
out=${DYNSCOPE_CAMPAIGN_OUT:-out}
source assets/recipes/progress.sh
case ${1:-test} in
  -h | --help)
    sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'
    exit 0
    ;;
esac
split=${1:-test}
export DYNSCOPE_CAMPAIGN_EPOCH=${2:-best}
case "$split $DYNSCOPE_CAMPAIGN_EPOCH" in
  val\ best | val\ last | test\ best | test\ last) ;;
  *)
    echo "usage: $0 [val|test] [best|last]  (--help explains)" >&2
    exit 2
    ;;
esac
# In the order of the claims: PointConv < GNN U-Net < non-object-centric; acc < vel; faces on < off.
evaluate_and_compare assets/recipes/movi-a-3k "$runs" "$out/campaign-evals/movi-a-3k" \
  "$out/campaign" "$split" \
  "pointconv_acc gnn_acc flat_acc pointconv_vel mesh_faces_on mesh_faces_off" \
  --data data/movi-a-3k --split "$split"
# The paper's size, in the same order (its faces-off runs relate objects at level 0 only, as the
# faces-on network does; mesh_faces_on_t06 is faces on with the interaction threshold at the
# relational radius, 0.6 instead of 0.4, the value chosen on the validation split; the *_r09 runs
# relate objects within 0.9 at level 0 instead of 0.6, the radius chosen on the validation split,
# both object-centric U-Nets and the velocity head at it so that they compare like for like; the
# non-object-centric U-Net has no relational units).
evaluate_and_compare assets/recipes/movi-a-3k "$runs" "$out/campaign-evals/movi-a-3k" \
  "$out/campaign-c32l4" "$split" \
  "pointconv_acc_r09_c32l4 gnn_acc_r09_c32l4 pointconv_vel_r09_c32l4
   pointconv_acc_c32l4 gnn_acc_c32l4 flat_acc_c32l4 pointconv_vel_c32l4
   mesh_faces_on_c32l4 mesh_faces_on_t06_c32l4 mesh_faces_off_c32l4" \
  --data data/movi-a-3k --split "$split"
# Faces on against off where faces are large (the same scenes with sparse meshes; faces on
# samples them at most 0.3 apart).
evaluate_and_compare assets/recipes/movi-a-3k "$runs" "$out/campaign-evals/movi-a-3k-sparse" \
  "$out/campaign-sparse" "$split" \
  "mesh_faces_on_sparse_c32l4 mesh_faces_off_sparse_c32l4" \
  --data data/movi-a-3k-sparse --split "$split"
# Trained on their own one-step predictions (pushforward, the *_pf1 recipes): the paper's size, each
# U-Net and the velocity head as in the group above, beside the same runs trained without it (so
# that each pushforward run's gain over its plain recipe is paired per scene too).
evaluate_and_compare assets/recipes/movi-a-3k "$runs" "$out/campaign-evals/movi-a-3k" \
  "$out/campaign-pf1" "$split" \
  "pointconv_acc_r09_pf1_c32l4 gnn_acc_r09_pf1_c32l4 flat_acc_pf1_c32l4 pointconv_vel_r09_pf1_c32l4
   pointconv_acc_r09_c32l4 gnn_acc_r09_c32l4 flat_acc_c32l4 pointconv_vel_r09_c32l4" \
  --data data/movi-a-3k --split "$split"
