#!/bin/sh
# Rewrites tests/render/golden/*.png from the current renderer (OSMesa). Usage:
#   tests/render/update_goldens.sh [BUILD_DIR]     (default: build)
# Look at the images before committing them.
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-"$root/build"}
cmake --build "$build" --target render_test
DYNSCOPE_UPDATE_GOLDEN=1 "$build/bin/render_test" --gtest_filter='Golden.*'
echo "goldens updated in $root/tests/render/golden (review with an image viewer, then commit)"
