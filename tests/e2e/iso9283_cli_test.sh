#!/usr/bin/env bash
# `hivecal iso9283` end to end, its sanity checks (docs/iso9283.md): fewer than 30 cycles per
# pose is a warning; with a calibration whose frame does not match the measurements (AP_P
# beyond the plausibility bound) every output is written and the exit is 5, the warning naming
# the cause (the tracker moved: registered again the reaches fit; or a model that does not
# predict them) and the remedy (`calibrate --robot-model RESULT --fit base`); --tool is refused
# with --calibration, and its default is calibrate's.
#   iso9283_cli_test.sh <hivecal binary> [emulator words...]
set -u
source "$(dirname "$0")/cli_lib.sh" "$@"

# A UR5 calibration with its own metrics: held-out MAE 0.2 mm, so the bound is 2 mm.
identity="[[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]"
ur_result_json ur5 0.089159 -0.425 -0.39225 0.10915 0.09465 0.0823 "0.0, 0.0, 0.1" "$identity" |
  sed 's/^  "base_to_tracker": /  "metrics": {"test": {"count": 10, "mae_m": {"x": 1e-4, "y": 1e-4, "z": 1e-4, "3d": 2e-4}}},\n  "base_to_tracker": /' \
    >"$work/cal.json"
# The same arm with a2 30 mm longer: it does not predict the reaches, whatever its base.
ur_result_json ur5 0.089159 -0.455 -0.39225 0.10915 0.09465 0.0823 "0.0, 0.0, 0.1" "$identity" >"$work/other_arm.json"
printf 'q1,q2,q3,q4,q5,q6\n0.1,-1.2,1.3,-0.4,0.8,0.2\n-0.5,-1.0,1.6,-0.9,1.2,0.4\n0.9,-1.7,1.1,0.3,0.5,-0.6\n1.6,-0.6,0.7,-1.5,1.0,0.9\n-1.2,-2.0,2.0,0.6,-0.8,-0.3\n' \
  >"$work/poses.csv"
"${run[@]}" predict --calibration "$work/cal.json" --joints "$work/poses.csv" --out "$work/commanded.csv" 2>/dev/null

# reaches CYCLES [ROTATION_RAD DX_M]: every pose reached CYCLES times on a 20 um square around its
# commanded point shifted by (30, -40, 0) um (AP_P 0.0500 mm), the tracker turned about z by
# ROTATION_RAD and moved by DX_M in x.
reaches() {
  paste -d, "$work/poses.csv" "$work/commanded.csv" | awk -F, -v n="$1" -v r="${2:-0}" -v dx="${3:-0}" '
    NR == 1 { print "q1,q2,q3,q4,q5,q6,x,y,z"; next }
    { pose[NR] = $0 }
    END { c = cos(r); s = sin(r)
      for (k = 0; k < n; ++k) for (i = 2; i <= NR; ++i) { split(pose[i], f, ",")
        ex = (k % 4 == 0 || k % 4 == 3) ? 10e-6 : -10e-6; ey = (k % 4 < 2) ? 10e-6 : -10e-6
        x = f[7] + 30e-6 + ex; y = f[8] - 40e-6 + ey
        printf "%s,%s,%s,%s,%s,%s,%.9f,%.9f,%.9f\n", f[1], f[2], f[3], f[4], f[5], f[6], c * x - s * y + dx, s * x + c * y, f[9] } }'
}
reaches 32 >"$work/r30.csv"
reaches 4 >"$work/r4.csv"
reaches 32 0.05 0.2 >"$work/moved.csv"

# --- 32 cycles in the calibration's frame: exit 0, no warning
"${run[@]}" iso9283 --samples "$work/r30.csv" --calibration "$work/cal.json" --out "$work/a.csv" >"$work/a.txt" 2>"$work/a.err"
code=$?
if [ "$code" -eq 0 ] && [ ! -s "$work/a.err" ] && [ "$(grep -c ',32,0.0500,0.0300,-0.0400,0.0000,0.0141$' "$work/a.csv")" -eq 5 ]; then pass; else
  fail "iso9283 on 30 cycles: exit $code, $(cat "$work/a.err" "$work/a.csv")"; fi

# --- 4 cycles: the same figures, a warning, exit 0; the page carries the warning too
"${run[@]}" iso9283 --samples "$work/r4.csv" --calibration "$work/cal.json" --out "$work/b.csv" --report "$work/b.html" \
  >"$work/b.txt" 2>"$work/b.err"
code=$?
if [ "$code" -eq 0 ] && grep -q "warning: 5 of 5 poses have fewer than 30 cycles (the fewest 4): ISO 9283 asks for 30" "$work/b.err" &&
   grep -q "<li>warning: 5 of 5 poses have fewer than 30 cycles" "$work/b.html" &&
   [ "$(grep -c ',4,0.0500,0.0300,-0.0400,0.0000,0.0141$' "$work/b.csv")" -eq 5 ]; then pass; else
  fail "iso9283 on 4 cycles: exit $code, $(cat "$work/b.err")"; fi

# --- the tracker set up anew (turned 0.05 rad, moved 0.2 m): exit 5, every output written, the
# cause and the remedy named
"${run[@]}" iso9283 --samples "$work/moved.csv" --calibration "$work/cal.json" --out "$work/c.csv" --report "$work/c.html" \
  >"$work/c.txt" 2>"$work/c.err"
code=$?
if [ "$code" -eq 5 ] && [ "$(wc -l <"$work/c.csv")" -eq 6 ] && [ -s "$work/c.html" ] &&
   grep -q "5 of 5 poses have AP_P beyond the plausibility bound 2.0000 mm (10 x the calibration's own held-out MAE of 0.2000 mm, at least 1 mm)" "$work/c.err" &&
   grep -q "does not match these measurements (registered again on these reaches, the base -> tracker moves the commanded points by up to" "$work/c.err" &&
   grep -q "the tracker was set up anew or moved since the calibration" "$work/c.err" &&
   grep -qF "hivecal calibrate --robot-model $work/cal.json --fit base --samples $work/moved.csv" "$work/c.err"; then pass; else
  fail "iso9283 with the tracker moved: exit $code, $(cat "$work/c.err")"; fi

# --- a calibration of another arm: exit 5, the model named as the cause
"${run[@]}" iso9283 --samples "$work/r30.csv" --calibration "$work/other_arm.json" --out "$work/d.csv" >"$work/d.txt" 2>"$work/d.err"
code=$?
if [ "$code" -eq 5 ] && [ -s "$work/d.csv" ] && grep -q "(1 mm: the calibration holds no metrics)" "$work/d.err" &&
   grep -q "the calibration does not predict these poses, not even with its base registered again" "$work/d.err" &&
   grep -q -- "--fit base" "$work/d.err"; then pass; else
  fail "iso9283 with another arm's calibration: exit $code, $(cat "$work/d.err")"; fi

# --- --tool: not with a calibration (its tool is calibrated); its default is calibrate's
expect 2 "--tool goes with --robot-model: a calibration result carries its own calibrated tool point" -- \
  iso9283 --samples "$work/r30.csv" --calibration "$work/cal.json" --tool 0,0,0.2
no_file "$work/e.csv"
default_tool() { "${run[@]}" "$1" --help 2>&1 | grep -A2 -- "--tool" | grep -o 'default: [0-9][0-9.,]*' | head -1; }
if [ "$(default_tool calibrate)" = "default: 0,0,0.1695" ] && [ "$(default_tool iso9283)" = "default: 0,0,0.1695" ] &&
   [ "$(default_tool plan)" = "default: 0,0,0.1695" ]; then pass; else
  fail "default --tool: calibrate '$(default_tool calibrate)', iso9283 '$(default_tool iso9283)', plan '$(default_tool plan)'"; fi
# With --robot-model FILE the description's tool (0.1 m here), as calibrate does.
if "${run[@]}" iso9283 --samples "$work/r30.csv" --robot-model "$work/other_arm.json" --out "$work/f.csv" 2>/dev/null |
     grep -q "tool 0.0000, 0.0000, 100.0000 mm; base -> tracker fitted to the reaches"; then pass; else
  fail "iso9283 --robot-model FILE: not the description's tool"; fi

finish
