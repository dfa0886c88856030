# Sourced by assets/recipes/run.sh and the campaigns' evaluate.sh: a run's progress as its
# checkpoint's recipe records it.
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
