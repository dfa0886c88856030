#!/usr/bin/env bash
# Drives the real viewer window (GLFW) under Xvfb as a user would: real mouse clicks and key
# presses through xdotool, screenshots through ffmpeg's x11grab. Not part of ctest (it needs
# xvfb, xdotool and ffmpeg); run by hand after a build:
#   tests/app/xvfb_session.sh ROLLOUT.h5 OUT_DIR
# Writes OUT_DIR/{start,home_right14,picked,side_by_side}.png and fails if a key or click had no
# effect (checked by comparing screenshots). The pick clicks a predicted point (found with
# python3 and numpy in a raw grab) with the inspector open: picked.png shows what it selected.
set -euo pipefail
rollout=${1:?usage: xvfb_session.sh ROLLOUT.h5 OUT_DIR}
out=${2:?usage: xvfb_session.sh ROLLOUT.h5 OUT_DIR}
dynscope=${DYNSCOPE:-build/bin/dynscope}
mkdir -p "$out"
export DISPLAY=:${XVFB_DISPLAY:-97}
Xvfb "$DISPLAY" -screen 0 1280x800x24 >/dev/null 2>&1 &
xvfb=$!
trap 'kill $viewer $xvfb 2>/dev/null || true' EXIT
sleep 2
"$dynscope" view "$rollout" --size 1280x800 &
viewer=$!
sleep 8
shot() { ffmpeg -loglevel error -y -f x11grab -video_size 1280x800 -i "$DISPLAY" -frames:v 1 "$out/$1.png"; }
# A key must stay down across a frame for the UI to see it, as a person's key press does.
press() { xdotool keydown "$1"; sleep 0.1; xdotool keyup "$1"; sleep 0.1; }
shot start
xdotool mousemove 800 600
press Home
for _ in $(seq 14); do press Right; done
sleep 0.5
shot home_right14
# Open "Selection & neighbourhood", show the prediction only, then click an error-coloured
# point right of the panels: the inspector must name the prediction, and the point is marked.
xdotool mousemove 60 456 click 1
sleep 0.5
xdotool mousemove 18 156 click 1  # "prediction" in the Rollout section
sleep 1
ffmpeg -loglevel error -y -f x11grab -video_size 1280x800 -i "$DISPLAY" -frames:v 1 \
  -f rawvideo -pix_fmt rgb24 "$out/grab.rgb"
read -r px py < <("${PYTHON:-python3}" - "$out/grab.rgb" <<'PY'
import sys, numpy as np
a = np.fromfile(sys.argv[1], np.uint8).reshape(800, 1280, 3).astype(int)
r, g, b = a[:, :, 0], a[:, :, 1], a[:, :, 2]
# Viridis' middle (teal: green and blue high, red low) is on points only: not the white
# background, the grey grid, the red and green axes or the pale translucent meshes.
score = np.where((b > 100) & (r < 90) & (g > 110), g + b - 2 * r, -1)
score[:, :400] = -1
score[660:, :] = -1
y, x = np.unravel_index(np.argmax(score), score.shape)
print(x, y)
PY
)
xdotool mousemove "$px" "$py"
sleep 0.3
xdotool click 1
sleep 1
xdotool mousemove 1200 620
sleep 0.5
shot picked
xdotool mousemove 18 179 click 1  # "side by side" in the Rollout section
sleep 1
shot side_by_side
cmp -s "$out/start.png" "$out/home_right14.png" && { echo "keys had no effect" >&2; exit 1; }
cmp -s "$out/home_right14.png" "$out/picked.png" && { echo "the pick had no effect" >&2; exit 1; }
cmp -s "$out/picked.png" "$out/side_by_side.png" && { echo "click had no effect" >&2; exit 1; }
rm -f "$out/grab.rgb"
echo "screenshots in $out"
