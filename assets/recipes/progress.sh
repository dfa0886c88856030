# Sourced by assets/recipes/run.sh and the campaigns' evaluate.sh: a run's progress as its
# checkpoint's recipe records it, and the campaigns' evaluation over seeds.
# run_progress CKPT prints "DONE TOTAL" (steps done, steps planned), or nothing without a recipe.
run_progress() {
  local recipe="$1.recipe.json"
  [ -f "$recipe" ] || return 0
  local done_steps total_steps
  done_steps=$(sed -n 's/^ *"steps": \([0-9]*\).*/\1/p' "$recipe" | head -1)
  total_steps=$(sed -n 's/^ *"total_steps": \([0-9]*\).*/\1/p' "$recipe" | head -1)
  echo "$done_steps $total_steps"
}
# run_finished CKPT succeeds when the run has done every planned step.
run_finished() {
  local done_steps total_steps
  read -r done_steps total_steps <<< "$(run_progress "$1")"
  [ -n "$done_steps" ] && [ "$done_steps" = "$total_steps" ]
}
# evaluate_and_compare RECIPES RUNS EVALS OUT SPLIT "VARIANT ..." EVAL_ARG ...
# The campaigns' evaluation: for each variant (in the order of its claims), every recipe
# RECIPES/VARIANT_sN.json whose run RUNS/NAME.pt has finished has its best-epoch checkpoint
# evaluated once into EVALS/NAME.SPLIT.json (`$dynscope eval --checkpoint BEST EVAL_ARG ... --threads
# 1`; again only when the checkpoint is newer); runs still training are reported and skipped.
# Then `$dynscope compare` over the variants' seeds, into OUT/compare.SPLIT.{txt,json}. EVALS holds
# the evaluations of one data set under one protocol and may be shared by several groups (OUT), so
# that a run compared in two groups is evaluated once.
# DYNSCOPE_CAMPAIGN_EPOCH=last reads each run's last epoch (RUNS/NAME.pt) instead of its best, into
# EVALS/NAME.last.SPLIT.json and OUT/compare.last.SPLIT.{txt,json}: the same runs without the choice
# of the epoch on validation.
evaluate_and_compare() {
  local recipes=$1 runs=$2 evals=$3 out=$4 split=$5 variants=$6
  shift 6
  local groups=() files variant recipe name ckpt chosen json
  local epoch=${DYNSCOPE_CAMPAIGN_EPOCH:-best} tag
  case $epoch in
    best) tag=$split ;;
    last) tag=last.$split ;;
    *)
      echo "DYNSCOPE_CAMPAIGN_EPOCH must be best or last, not '$epoch'" >&2
      return 2
      ;;
  esac
  mkdir -p "$evals" "$out"
  for variant in $variants; do
    files=()
    for recipe in "$recipes/${variant}"_s[0-9].json; do
      [ -f "$recipe" ] || continue
      name=$(basename "$recipe" .json)
      ckpt=$runs/$name.pt
      [ -f "$ckpt.recipe.json" ] || continue
      if ! run_finished "$ckpt"; then
        echo "$name: still training ($(run_progress "$ckpt" | sed 's/ / of /') steps), skipped"
        continue
      fi
      chosen=$runs/$name.best.pt
      [ "$epoch" = last ] && chosen=$ckpt
      json=$evals/$name.$tag.json
      if [ ! -f "$json" ] || [ "$chosen" -nt "$json" ]; then
        echo "$name: evaluating $chosen on the $split split"
        "$dynscope" eval --checkpoint "$chosen" "$@" --threads 1 --json "$json" \
          > "$evals/$name.$tag.txt"
      fi
      files+=("$json")
    done
    if [ ${#files[@]} -gt 0 ]; then
      groups+=("$variant=$(IFS=,; echo "${files[*]}")")
    fi
  done
  if [ ${#groups[@]} -eq 0 ]; then
    echo "no finished run to compare"
    return 0
  fi
  "$dynscope" compare "${groups[@]}" --json "$out/compare.$tag.json" | tee "$out/compare.$tag.txt"
}
