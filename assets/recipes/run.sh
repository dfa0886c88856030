#!/usr/bin/env bash
# Runs or continues campaign recipes (runs trained in sittings), one after another:
#   assets/recipes/run.sh [RECIPE.json ...]   (default: every recipe of the movi-a campaign,
#                                             assets/recipes/movi-a-3k/*_sN.json)
# A recipe's "out" names its checkpoint (under assets/runs/, kept in git with its training state).
# A run whose training state exists is continued exactly where it stopped (`--resume`); a finished
# run (its recipe's progress says all steps are done; its state is then no longer kept) is left as
# it is. Stop at any time: the state is saved every `checkpoint_every` steps. Two runs at once
# (one per core, each with one compute thread) are the fastest use of a 2-core machine.
set -euo pipefail
cd "$(dirname "$0")/../.."
dynscope=${DYNSCOPE:-build/bin/dynscope}
source assets/recipes/progress.sh
recipes=("$@")
[ ${#recipes[@]} -eq 0 ] && recipes=(assets/recipes/movi-a-3k/*_s[0-9].json)
for recipe in "${recipes[@]}"; do
  name=$(basename "$recipe" .json)
  ckpt=$(sed -n 's/^  "out": "\([^"]*\)".*/\1/p' "$recipe" | head -1)
  if [ -z "$ckpt" ]; then
    echo "$recipe: no \"out\" checkpoint path" >&2
    exit 1
  fi
  mkdir -p "$(dirname "$ckpt")"
  resume=()
  if run_finished "$ckpt"; then
    echo "$name: finished ($(run_progress "$ckpt" | cut -d' ' -f1) steps)"
    continue
  fi
  [ -f "$ckpt.state" ] && resume=(--resume)
  if [ ${#resume[@]} -gt 0 ]; then echo "$name: continuing"; else echo "$name: starting"; fi
  "$dynscope" train --recipe "$recipe" "${resume[@]}"
done
