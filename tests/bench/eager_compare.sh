#!/usr/bin/env bash
# Inference speed of our network against the same network in plain PyTorch eager ops
# (tests/bench/eager_network.py), both on one thread on this machine: the Physion-preset PointConv
# U-Net on model_bench's synthetic scene at 3k and 10k points. Each round runs the C++ side
# (network_export: fused and unfused forward passes, taking turns) and then the eager side on the
# exported weights and input, which also checks that its output equals ours; the table takes the
# minimum of each column over the rounds. Builds nothing.
#
# Optional, not part of the build or CTest: the product does not use Python. It needs Debian 12's
# python3-torch (the PyTorch 1.13.1 that libtorch-dev comes from) for the system Python:
#   apt-get install -y python3-torch python3-numpy
#   cmake --build build --target network_export
#   tests/bench/eager_compare.sh [ROUNDS] [REPEATS]     (default 3 rounds of 20 forward passes)
# PYTHON (default /usr/bin/python3) and NETWORK_EXPORT (default build/bin/network_export) override
# the programs. The eager side runs twice per round: with glibc's default malloc settings (what a
# Python process gets) and with those our programs set (engine/model/torch_runtime.cpp: freed memory
# kept up to 128 MiB, mmap only above 32 MiB), which removes its page faults; both rows are shown.
set -euo pipefail
cd "$(dirname "$0")/../.."
export_bin=${NETWORK_EXPORT:-build/bin/network_export}
python=${PYTHON:-/usr/bin/python3}
usage="usage: tests/bench/eager_compare.sh [ROUNDS] [REPEATS]   (default 3 rounds of 20 passes)"
case "${1:-}" in -h | --help) echo "$usage"; exit 0 ;; esac
rounds=${1:-3}
repeats=${2:-20}
[[ "$rounds" =~ ^[1-9][0-9]*$ && "$repeats" =~ ^[1-9][0-9]*$ ]] || {
  echo "eager_compare: ROUNDS and REPEATS must be positive integers" >&2
  echo "$usage" >&2
  exit 2
}
script=tests/bench/eager_network.py
[ -x "$export_bin" ] || { echo "eager_compare: $export_bin missing (cmake --build build --target network_export)" >&2; exit 1; }
"$python" -c "import torch" 2>/dev/null || { echo "eager_compare: $python has no torch (apt-get install python3-torch)" >&2; exit 1; }

# One compute thread on both sides; OpenBLAS (OpenMP build) follows OMP_NUM_THREADS.
export DYNSCOPE_BENCH_THREADS=1 OMP_NUM_THREADS=1
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
echo "== $(uptime)"
for ((r = 1; r <= rounds; ++r)); do
  echo "== round $r of $rounds"
  sizes=(--points 3000,10000 --repeats "$repeats")
  if [ "$r" -eq 1 ]; then "$export_bin" "$dir" "${sizes[@]}"; else "$export_bin" "$dir" "${sizes[@]}" | grep points; fi
  files=("$dir"/network_3000.pt "$dir"/network_10000.pt)
  "$python" "$script" "${files[@]}" --repeats "$repeats" --label "eager, glibc malloc defaults" \
    --results "$dir/results.jsonl"
  MALLOC_MMAP_THRESHOLD_=$((32 << 20)) MALLOC_TRIM_THRESHOLD_=$((128 << 20)) \
    MALLOC_TOP_PAD_=$((16 << 20)) "$python" "$script" "${files[@]}" --repeats "$repeats" \
    --label "eager, our malloc settings" --results "$dir/results.jsonl"
done
echo "== $(uptime)"
"$python" "$script" --summary "$dir/results.jsonl"
