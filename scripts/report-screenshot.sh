#!/usr/bin/env bash
# A PNG of the demo session's report (scripts/demo.sh's session: simulate --seed 1, calibrate
# from the captures) into docs/img/report.png, rendered by headless Chromium.
#   scripts/report-screenshot.sh [OUT.png]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-docs/img/report.png}
command -v chromium >/dev/null || { echo "report-screenshot: chromium is missing (scripts/install-deps.sh)" >&2; exit 1; }
cmake --preset host >/dev/null
cmake --build build/host -j2 --target hivecal_cli >/dev/null
hivecal=build/host/apps/hivecal/hivecal
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$hivecal" simulate --out-dir "$work" --seed 1 >/dev/null
"$hivecal" calibrate --robot "$work/robot.cap" --tracker "$work/tracker.cap" --robot-model ur5 \
  --out "$work/result.json" --report "$work/report" --quiet >/dev/null
mkdir -p "$(dirname "$out")"
# The figures start below the tables: the page from its top, 1300 x 5200 px.
chromium --headless --disable-gpu --no-sandbox --no-first-run --user-data-dir="$work/profile" --hide-scrollbars \
  --window-size=1300,5200 --screenshot="$(realpath -m "$out")" "file://$work/report/index.html" >/dev/null 2>&1
echo "report-screenshot: $out"
