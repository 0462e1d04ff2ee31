#!/usr/bin/env bash
# The demo session over real ttys: the simulator serves the robot and tracker streams on two
# pseudo-terminals, `hivecal record` reads them through the serial port code (termios raw,
# the spec's baud rates) into captures, and `hivecal calibrate` runs on what was recorded.
#   scripts/demo-live.sh [SPEED]   SPEED: session seconds per second (default 0: as fast as
#                                  the reader takes the bytes; 1: real time, 10 minutes)
# Outputs go to build/demo-live/.
set -euo pipefail
cd "$(dirname "$0")/.."
speed=${1:-0}
scripts/install-deps.sh
cmake --preset host >/dev/null
cmake --build --preset host -j"$(nproc)" --target hivecal_cli >/dev/null
hivecal=build/host/apps/hivecal/hivecal
out=build/demo-live
rm -rf "$out"
mkdir -p "$out"

echo "== serve: UR5 + tracker session on two ptys (speed ${speed}; 0 = unpaced)"
"$hivecal" simulate --serve --speed "$speed" --serve-delay-s 2 --out-dir "$out" --seed 1 >"$out/serve.log" &
server=$!
for _ in $(seq 1 50); do grep -q '^tracker ' "$out/serve.log" 2>/dev/null && break; sleep 0.1; done
robot_port=$(awk '$1 == "robot" { print $2 }' "$out/serve.log")
tracker_port=$(awk '$1 == "tracker" { print $2 }' "$out/serve.log")
[ -n "$robot_port" ] && [ -n "$tracker_port" ] || { echo "demo-live: the simulator did not open its ptys" >&2; exit 1; }
echo "robot on $robot_port, tracker on $tracker_port"

echo "== record both ports until the session ends"
"$hivecal" record --robot-port "$robot_port" --tracker-port "$tracker_port" \
  --robot-out "$out/robot.cap" --tracker-out "$out/tracker.cap" &
recorder=$!
wait "$server"
sleep 1                      # the last bytes reach the captures
kill -INT "$recorder"        # record flushes, fsyncs and exits on SIGINT
wait "$recorder" || true
cat "$out/serve.log" | tail -1

echo
echo "== calibrate from the recorded captures"
"$hivecal" calibrate --robot "$out/robot.cap" --tracker "$out/tracker.cap" --robot-model ur5 \
  --out "$out/result.json" --report "$out/report"
echo
echo "== validation against the simulator's noise-free truth on fresh poses"
"$hivecal" validate --calibration "$out/result.json" --truth "$out/truth.json" --seed 7
