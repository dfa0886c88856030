#!/usr/bin/env bash
# Runs or continues movi-a reproduction-campaign recipes, one after another:
#   assets/recipes/movi-a-3k/run.sh [RECIPE.json ...]   (default: every recipe of the campaign)
# A run whose training state exists is continued exactly where it stopped (`--resume`); a finished
# run (its recipe's progress says all steps are done; its state is then no longer kept) is left as
# it is. Stop at any time: the state is saved every 1000 steps. Two runs at once
# (one per core, each with one compute thread) are the fastest use of a 2-core machine.
set -euo pipefail
cd "$(dirname "$0")/../../.."
dynscope=${DYNSCOPE:-build/bin/dynscope}
recipes=("$@")
[ ${#recipes[@]} -eq 0 ] && recipes=(assets/recipes/movi-a-3k/*_s[0-9].json)
mkdir -p assets/runs/movi-a-3k
for recipe in "${recipes[@]}"; do
  name=$(basename "$recipe" .json)
  ckpt=assets/runs/movi-a-3k/$name.pt
  resume=()
  if [ -f "$ckpt.recipe.json" ]; then
    # The recipe beside the checkpoint records "steps" done and "total_steps" planned.
    done_steps=$(sed -n 's/^ *"steps": \([0-9]*\).*/\1/p' "$ckpt.recipe.json" | head -1)
    total_steps=$(sed -n 's/^ *"total_steps": \([0-9]*\).*/\1/p' "$ckpt.recipe.json" | head -1)
    if [ -n "$done_steps" ] && [ "$done_steps" = "$total_steps" ]; then
      echo "$name: finished ($done_steps steps)"
      continue
    fi
  fi
  [ -f "$ckpt.state" ] && resume=(--resume)
  if [ ${#resume[@]} -gt 0 ]; then echo "$name: continuing"; else echo "$name: starting"; fi
  "$dynscope" train --recipe "$recipe" "${resume[@]}"
done
