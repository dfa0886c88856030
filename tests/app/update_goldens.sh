#!/bin/sh
# Rewrites tests/app/golden/*.png from the current viewer (OSMesa, null platform). Usage:
#   tests/app/update_goldens.sh [BUILD_DIR]     (default: build)
# Look at the images before committing them.
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-"$root/build"}
cmake --build "$build" --target viewer_test
DYNSCOPE_UPDATE_GOLDEN=1 "$build/bin/viewer_test" --gtest_filter='ViewerGolden.*'
echo "goldens updated in $root/tests/app/golden (review with an image viewer, then commit)"
