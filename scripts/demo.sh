#!/usr/bin/env bash
# The main job: a simulated UR5 + laser tracker session (38 waypoints, ~600 s, own clocks,
# noise, beam losses, unmodelled joint compliance) written as serial captures, read back
# through the real serial code path (decoder -> clock sync -> quasi-static extraction),
# calibrated (ABC then Levenberg-Marquardt over the identifiable model), reported.
#   scripts/demo.sh [extra hivecal calibrate options]
# Outputs go to build/demo/: captures, CSV logs, truth, result.json, ur-deltas.conf, report/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
cmake --preset host >/dev/null
cmake --build --preset host -j"$(nproc)" --target hivecal_cli >/dev/null
hivecal=build/host/apps/hivecal/hivecal
out=build/demo
mkdir -p "$out"

echo "== simulate: UR5 + tracker session -> $out/robot.cap, $out/tracker.cap"
"$hivecal" simulate --out-dir "$out" --seed 1 --force
echo
echo "== calibrate from the captures"
"$hivecal" calibrate --robot "$out/robot.cap" --tracker "$out/tracker.cap" --robot-model ur5 \
  --out "$out/result.json" --ur-deltas "$out/ur-deltas.conf" --report "$out/report" "$@"
echo
echo "== validation against the simulator's noise-free truth on fresh poses"
"$hivecal" validate --calibration "$out/result.json" --truth "$out/truth.json" --seed 7
