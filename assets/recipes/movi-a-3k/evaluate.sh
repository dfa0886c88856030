#!/usr/bin/env bash
# Evaluates the finished runs of the movi-a reproduction campaign on its test split and compares
# them over seeds:
#   assets/recipes/movi-a-3k/evaluate.sh [SPLIT]      (default: test)
# Each finished run's best-epoch checkpoint (chosen on the validation split during training) is
# evaluated once into out/campaign/NAME.SPLIT.json (again only when the checkpoint is newer); runs
# still training are skipped. Then `dynscope compare` prints every variant's end error as mean ±
# sd over the seeds evaluated so far, and the paired per-scene comparisons behind the paper's
# claims, into out/campaign/compare.SPLIT.{txt,json}.
set -euo pipefail
cd "$(dirname "$0")/../../.."
dynscope=${DYNSCOPE:-build/bin/dynscope}
source assets/recipes/progress.sh
split=${1:-test}
runs=assets/runs/movi-a-3k
out=out/campaign
mkdir -p "$out"
# In the order of the claims: PointConv < GNN U-Net < non-object-centric; acc < vel; faces on < off.
variants=(pointconv_acc gnn_acc flat_acc pointconv_vel mesh_faces_on mesh_faces_off)
groups=()
for variant in "${variants[@]}"; do
  files=()
  for recipe in assets/recipes/movi-a-3k/"${variant}"_s[0-9].json; do
    name=$(basename "$recipe" .json)
    ckpt=$runs/$name.pt
    [ -f "$ckpt.recipe.json" ] || continue
    if ! run_finished "$ckpt"; then
      echo "$name: still training ($(run_progress "$ckpt" | sed 's/ / of /') steps), skipped"
      continue
    fi
    best=$runs/$name.best.pt
    json=$out/$name.$split.json
    if [ ! -f "$json" ] || [ "$best" -nt "$json" ]; then
      echo "$name: evaluating $best on the $split split"
      "$dynscope" eval --checkpoint "$best" --data data/movi-a-3k --split "$split" --threads 1 \
        --json "$json" > "$out/$name.$split.txt"
    fi
    files+=("$json")
  done
  if [ ${#files[@]} -gt 0 ]; then
    groups+=("$variant=$(IFS=,; echo "${files[*]}")")
  fi
done
if [ ${#groups[@]} -eq 0 ]; then
  echo "no finished run to compare"
  exit 0
fi
"$dynscope" compare "${groups[@]}" --json "$out/compare.$split.json" | tee "$out/compare.$split.txt"
