#!/usr/bin/env bash
# Drives the real viewer window (GLFW) under Xvfb as a user would: real mouse clicks and key
# presses through xdotool, screenshots through ffmpeg's x11grab. Not part of ctest (it needs
# xvfb, xdotool and ffmpeg); run by hand after a build:
#   tests/app/xvfb_session.sh ROLLOUT.h5 OUT_DIR
# Writes OUT_DIR/{start,home_right14,side_by_side}.png and fails if a key or click had no effect
# on the frame counter shown in the window title bar area (checked by comparing screenshots).
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
xdotool mousemove 18 179 click 1  # "side by side" in the Rollout section
sleep 1
shot side_by_side
cmp -s "$out/start.png" "$out/home_right14.png" && { echo "keys had no effect" >&2; exit 1; }
cmp -s "$out/home_right14.png" "$out/side_by_side.png" && { echo "click had no effect" >&2; exit 1; }
echo "screenshots in $out"
