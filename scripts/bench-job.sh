#!/usr/bin/env bash
# Wall time of the whole job on a 10-minute session: decode both captures, clock fit,
# extraction, default calibration (ABC then LM over the full model), tables, result.json,
# UR deltas and the HTML report. Runs it RUNS times (default 7) and prints each run and the
# median. Wall time depends on the machine's load: run it on a quiet machine.
#   scripts/bench-job.sh [RUNS]
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-7}
cmake --preset host >/dev/null
cmake --build --preset host -j"$(nproc)" --target hivecal_cli >/dev/null
hivecal=build/host/apps/hivecal/hivecal
out=build/bench-job
mkdir -p "$out"
"$hivecal" simulate --out-dir "$out" --seed 1 --force >/dev/null
echo "session: $(stat -c %s "$out/robot.cap") + $(stat -c %s "$out/tracker.cap") bytes of captures (600 s)"
TIMEFORMAT='%R %U %S'
walls=()
for i in $(seq 1 "$runs"); do
  t=$( { time "$hivecal" calibrate --robot "$out/robot.cap" --tracker "$out/tracker.cap" --out "$out/result.json" \
           --ur-deltas "$out/ur-deltas.conf" --report "$out/report" --quiet >/dev/null; } 2>&1 )
  read -r wall user sys <<<"$t"
  echo "run $i: wall ${wall} s, user ${user} s, sys ${sys} s"
  walls+=("$wall")
done
median=$(printf '%s\n' "${walls[@]}" | sort -n | awk '{ v[NR] = $1 } END { print v[int((NR + 1) / 2)] }')
echo "median wall time of the whole job: ${median} s (target < 1 s)"
