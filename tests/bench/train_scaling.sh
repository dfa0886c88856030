#!/usr/bin/env bash
# Data-parallel scaling of training on this machine, measured in one run: the default movi-a
# PointConv model (assets/recipes/movi-a_pointconv_acc.json's architecture and sampling) at an
# effective batch of 2, as 1 process x 2 threads against 2 processes x 1 thread (Gloo over
# loopback), plus the all-reduce time per step. Steps/s are taken from the training log after
# a warm-up, so start-up and data loading are not counted.
#   tests/bench/train_scaling.sh [STEPS]     (default 80; needs build/bin/dynscope)
set -euo pipefail
bin=${DYNSCOPE:-build/bin/dynscope}
steps=${1:-80}
warm=10
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
"$bin" info --system
"$bin" --log-level warn generate --scenario movi-a --count 24 --seed 77 --out "$dir/data" >/dev/null
model="--model pointconv --target acc --width 24 --levels 3 --bottleneck-blocks 2 --k 12
       --voxel 0.45 --radius 0.6 --sample-voxel 0.3 --lr 0.005"
common="--log-level warn train --data $dir/data $model --max-steps $steps --val-scenes 0
        --checkpoint-every 1000000 --seed 1"
rate() {  # steps per second between step $warm and the last step of a training log
  awk -F, -v w="$warm" 'NR > 1 { if ($1 == w) t0 = $6; last = $1; t = $6 }
    END { printf "%.2f", (last - w) / (t - t0) }' "$1"
}
# shellcheck disable=SC2086
"$bin" $common --batch 2 --threads 2 --out "$dir/one.pt" --log "$dir/one.csv" >/dev/null
# shellcheck disable=SC2086
out=$("$bin" $common --batch 1 --nproc 2 --threads 1 --out "$dir/two.pt" --log "$dir/two.csv" 2>&1)
echo "$out" | grep -E "all-reduce|world size" || true
bytes=$("$bin" info --json "$dir/one.pt" | sed -n 's/.*"parameters": *\([0-9]*\).*/\1/p' | head -n1)
echo "1 process x 2 threads, batch 2:      $(rate "$dir/one.csv") steps/s"
echo "2 processes x 1 thread, batch 1 each: $(rate "$dir/two.csv") steps/s"
[ -n "$bytes" ] && echo "gradient: $bytes parameters, $((bytes * 4)) bytes per all-reduce"
