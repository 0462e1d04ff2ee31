#!/usr/bin/env bash
# Command-line behaviour of the hivecal binary: bad inputs give a clear message, a
# non-zero documented exit code, no crash and no output file; good inputs work end to end.
#   cli_test.sh <hivecal binary> [emulator words...]
set -u
source "$(dirname "$0")/cli_lib.sh" "$@"

printf 'q1,q2,q3,q4,q5,q6\n0,-1.5707963267948966,1.5707963267948966,-1.5707963267948966,-1.5707963267948966,0\n' >"$work/joints.csv"
ur_result_json ur5 0.089159 -0.425 -0.39225 0.10915 0.09465 0.0823 "0.0, 0.0, 0.0" \
  "[[1, 0, 0, 1], [0, 1, 0, 2], [0, 0, 1, 3], [0, 0, 0, 1]]" >"$work/result.json"

# HIVECAL_CLI_TEST_SCOPE=golden (the presets that check bits only): the end-to-end run and
# its committed digest, not the behaviour checks around it.
scope=${HIVECAL_CLI_TEST_SCOPE:-all}
if [ "$scope" = all ]; then
# --- usage errors (exit 2)
expect 2 "unknown command 'frobnicate'" -- frobnicate
expect 2 "unknown option '--bogus'" -- predict --bogus
expect 2 "--joints and either --calibration or --robot-model are required" -- predict --joints "$work/joints.csv"
expect 2 "needs a value" -- predict --calibration
expect 2 "--frame must be 'tracker' or 'base'" -- predict --calibration "$work/result.json" --joints "$work/joints.csv" --frame world
# --- bad input files (exit 3), and no output left behind
expect 3 "cannot open" -- predict --calibration "$work/missing.json" --joints "$work/joints.csv" --out "$work/p1.csv"
no_file "$work/p1.csv"
: >"$work/empty.json"
expect 3 "empty file" -- predict --calibration "$work/empty.json" --joints "$work/joints.csv" --out "$work/p2.csv"
no_file "$work/p2.csv"
sed 's/"standard-dh"/"craig"/' "$work/result.json" >"$work/craig.json"
expect 3 "craig.json: unknown \"convention\" 'craig'" -- predict --calibration "$work/craig.json" --joints "$work/joints.csv" --out "$work/p3.csv"
no_file "$work/p3.csv"
head -c 200 "$work/result.json" >"$work/cut.json"
expect 3 "malformed JSON" -- predict --calibration "$work/cut.json" --joints "$work/joints.csv" --out "$work/p4.csv"
printf 'q1,q2,q3\n1,2,3\n' >"$work/badjoints.csv"
expect 3 "its header has 3 joint columns (q1..q3), but the robot model has 6 joints (q1..q6)" -- predict --calibration "$work/result.json" --joints "$work/badjoints.csv" --out "$work/p5.csv"
no_file "$work/p5.csv"
printf 'q1,q2,q3,q4,q5,q6\n0,0,inf,0,0,0\n' >"$work/infjoints.csv"
expect 3 "NaN or Inf" -- predict --calibration "$work/result.json" --joints "$work/infjoints.csv" --out "$work/p6.csv"
# --- output errors (exit 4)
expect 4 "does not exist" -- predict --calibration "$work/result.json" --joints "$work/joints.csv" --out "$work/no/dir/p.csv"

# --- record: usage errors
expect 2 "give --robot-port and/or --tracker-port" -- record
expect 2 "--robot-baud: unsupported baud rate 1234" -- record --robot-port /dev/null --robot-baud 1234

# --- calibrate: bad inputs
expect 2 "give either --samples, or --robot and --tracker" -- calibrate
expect 2 "--robot and --tracker go together" -- calibrate --robot "$work/joints.csv"
expect 2 "unknown robot model 'ur7'" -- calibrate --samples "$work/joints.csv" --robot-model ur7
printf '{"convention": "modified-dh", "dh": []}\n' >"$work/arm.json"
expect 3 "arm.json: \"dh\" must be an array of 1 to 8 joint objects, one per joint (it has 0 rows)" -- calibrate --samples "$work/joints.csv" --robot-model "$work/arm.json"
expect 3 "no-such-arm.json': cannot open" -- calibrate --samples "$work/joints.csv" --robot-model "$work/no-such-arm.json"
expect 2 "--method must be one of" -- calibrate --samples "$work/joints.csv" --method sgd
expect 2 "--split must be within (0, 1]" -- calibrate --samples "$work/joints.csv" --split 1.5
expect 2 "--tool must be X,Y,Z" -- calibrate --samples "$work/joints.csv" --tool 1,2
expect 3 "unexpected header" -- calibrate --samples "$work/joints.csv" --out "$work/r1.json"
no_file "$work/r1.json"
printf 'q1,q2,q3,q4,q5,q6,x,y,z\n' >"$work/s.csv"
for i in 1 2 3 4 5; do printf '0,-1.5,1.5,-1.5,-1.5,0,1,2,3\n' >>"$work/s.csv"; done
expect 3 "at least 3 samples at non-collinear tool points" -- calibrate --samples "$work/s.csv" --out "$work/r2.json"
no_file "$work/r2.json"
for i in $(seq 1 40); do printf '0,-1.5,1.5,-1.5,-1.5,0,1,2,3\n' >>"$work/s.csv"; done
expect 3 "cannot fit the tracker frame" -- calibrate --samples "$work/s.csv" --out "$work/r3.json"
no_file "$work/r3.json"
# Noise that starts with a control byte, so it is a capture whatever the random bytes are.
{ printf '\001'; head -c 3000 /dev/urandom | tr -d '\000' | head -c 2000; } >"$work/noise.cap"
printf '\000' >>"$work/noise.cap"
expect 3 "no valid frame" -- calibrate --robot "$work/noise.cap" --tracker "$work/noise.cap" --out "$work/r4.json"
no_file "$work/r4.json"

# --- a good prediction: UR5 at the zero-like pose through a pure translation
if "${run[@]}" predict --calibration "$work/result.json" --joints "$work/joints.csv" --out "$work/p.csv" &&
   [ "$(head -1 "$work/p.csv")" = "x,y,z" ] && [ "$(wc -l <"$work/p.csv")" -eq 2 ]; then
  pass
else
  fail "predict on good input"
fi
fi  # scope all
# --- end to end: simulated captures and CSV logs -> calibrate -> result.json -> predict
sim="$work/sim/session"  # a folder that does not exist yet: simulate creates it
if "${run[@]}" simulate --out-dir "$sim" --waypoints 12 --duration-s 150 --seed 5 >/dev/null; then
  pass
else
  fail "simulate --out-dir (new folder)"
fi
# Captures, CSV logs and a mix give the same samples (calibrate reads its inputs as extract
# does, streams::load_session, and the samples file holds every bit: %.17g), so one calibration
# stands for the three.
extracted() {  # extracted NAME ROBOT TRACKER: the samples the inputs give, in NAME.csv
  "${run[@]}" extract --robot "$2" --tracker "$3" --samples "$work/$1.csv" >"$work/$1.out" 2>&1
}
if "${run[@]}" calibrate --robot "$sim/robot.cap" --tracker "$sim/tracker.cap" --out "$work/cap.json" >"$work/cap.out" 2>&1 &&
   extracted cap_samples "$sim/robot.cap" "$sim/tracker.cap" && extracted csv_samples "$sim/robot_joints.csv" "$sim/tracker.csv" &&
   extracted mixed_samples "$sim/robot_joints.csv" "$sim/tracker.cap" && grep -q "robot   hivecal robot log: " "$work/csv_samples.out" &&
   cmp -s "$work/cap_samples.csv" "$work/csv_samples.csv" && cmp -s "$work/cap_samples.csv" "$work/mixed_samples.csv"; then
  pass
else
  fail "captures, CSV logs and a mix must give the same samples"
  cat "$work/csv_samples.out" "$work/mixed_samples.out"
fi
# The same command writes the same bytes at every run and on every target (x86-64, aarch64 and
# armhf run this script): result files hold no wall-clock times, and the digest of the result of
# this simulated session (simulate --seed 5 --waypoints 12 --duration-s 150) is committed.
# Update the digest only for an intended change of the computation or the format.
if ! grep -q '"seconds"' "$work/cap.json"; then pass; else fail "a result file holds run times"; fi
result_sha256=53d4ca9c337d126c2c4d8bd363175f3f42de8f02065996cafe89031db30b5a1e
if [ "$(sha256sum <"$work/cap.json" | cut -d' ' -f1)" = "$result_sha256" ]; then
  pass
else
  fail "result.json differs from the committed digest: $(sha256sum <"$work/cap.json")"
fi
if [ "$scope" = golden ]; then
  finish
  exit
fi
# `report` redraws the page from a result; a result without the report key, or with a damaged
# one, is bad input naming the key.
expect 2 "--calibration and --out are required" -- report --out "$work/redrawn"
awk '/^  "report": /{exit} {lines[n++]=$0} END{for(i=0;i<n-1;i++)print lines[i]; l=lines[n-1]; sub(/,$/,"",l); print l; print "}"}' \
  "$work/cap.json" >"$work/no_report.json"
expect 3 'no "report" key' -- report --calibration "$work/no_report.json" --out "$work/redrawn"
sed 's/"q_rad"/"q_deg"/' "$work/cap.json" >"$work/bad_report.json"
expect 3 '"report"."samples" is malformed' -- report --calibration "$work/bad_report.json" --out "$work/redrawn"
if "${run[@]}" report --calibration "$work/cap.json" --out "$work/redrawn" >/dev/null &&
   grep -q "<svg" "$work/redrawn/index.html"; then pass; else
  fail "report --calibration of a calibrate result"; fi
# Predict the simulator's noise-free static points from their joints (truth_samples.csv:
# waypoint,t_tracker,t_robot,q1..q6,x,y,z): the calibration must be far better than nominal.
{ echo "q1,q2,q3,q4,q5,q6"; tail -n +2 "$sim/truth_samples.csv" | cut -d, -f4-9; } >"$work/truth_joints.csv"
if "${run[@]}" predict --calibration "$work/cap.json" --joints "$work/truth_joints.csv" --out "$work/pred.csv"; then
  mean_um=$(paste -d, <(tail -n +2 "$sim/truth_samples.csv" | cut -d, -f10-12) <(tail -n +2 "$work/pred.csv") |
    awk -F, '{ d = sqrt(($1-$4)^2 + ($2-$5)^2 + ($3-$6)^2); s += d; n++ } END { if (n == 0) print 1e9; else printf "%.1f", 1e6 * s / n }')
  if awk -v m="$mean_um" 'BEGIN { exit !(m < 60) }'; then pass; else
    fail "predict vs truth: mean error $mean_um um (want < 60 um)"; fi
  echo "predict vs noise-free truth: mean error $mean_um um"
else
  fail "predict on the calibration of the captures"
fi
# A small paired-sample set (one noise-free sample per waypoint) with a 0.6 m blunder on file
# line 5: set aside and named by file and line; --split 1 trains on all; --cv writes its folds.
{ echo "q1,q2,q3,q4,q5,q6,x,y,z"; tail -n +2 "$sim/truth_samples.csv" | awk -F, '!seen[$1]++' | cut -d, -f4-12 |
  awk -F, -v OFS=, 'NR == 4 { $7 += 0.35; $8 -= 0.4; $9 += 0.3 } { print }'; } >"$work/blunder.csv"
if "${run[@]}" calibrate --samples "$work/blunder.csv" --method lm --split 1 --cv 3 --out "$work/small.json" \
     >"$work/small.out" 2>&1 && grep -q "set aside as a blunder: $work/blunder.csv:5, residual 6" "$work/small.out" &&
   grep -q "Cross-validation (3 folds over" "$work/small.out" && grep -q '"source": "'"$work"'/blunder.csv:5"' "$work/small.json" &&
   grep -q '"cross_validation"' "$work/small.json" && ! grep -q '"test_mae_m"' "$work/small.json"; then ok=1; else ok=0; fi
if [ "$ok" = 1 ]; then pass; else
  fail "blunder set aside by file:line, --split 1, --cv 3"; cat "$work/small.out"; fi
# Kept, the blunder drags the fit: the plausibility check warns (exit 5), the result is written.
"${run[@]}" calibrate --samples "$work/blunder.csv" --method lm --split 1 --keep-outliers --out "$work/kept.json" \
  >"$work/kept.out" 2>&1
kept_rc=$?
if [ "$kept_rc" = 5 ] && grep -q "warning: .* moved" "$work/kept.out" && ! grep -q "set aside" "$work/kept.out" &&
   grep -q '"outliers": \[\]' "$work/kept.json"; then
  pass
else
  fail "--keep-outliers"; cat "$work/kept.out"
fi
expect 2 "--cv must be within [2, 128] folds, or 'loo', got '1'" -- calibrate --samples "$work/blunder.csv" --cv 1
# A CSV log with a bad row is a clear error naming file and line, and no result.
{ head -5 "$sim/tracker.csv"; echo "5.9,1,2"; } >"$work/short_tracker.csv"
expect 3 "short_tracker.csv:6: 3 fields where the header has 5" -- calibrate --robot "$sim/robot_joints.csv" --tracker "$work/short_tracker.csv" --out "$work/r5.json"
no_file "$work/r5.json"
{ head -3 "$sim/robot_joints.csv"; head -2 "$sim/robot_joints.csv" | tail -1; } >"$work/backwards.csv"
expect 3 "does not increase" -- calibrate --robot "$work/backwards.csv" --tracker "$sim/tracker.csv" --out "$work/r6.json"
no_file "$work/r6.json"
printf 't,q1,q2,q3,q4,q5,q6\n-1,0,0,0,0,0,0\n' >"$work/negative.csv"
expect 3 "outside 0 .. 1.8e13 s" -- calibrate --robot "$work/negative.csv" --tracker "$sim/tracker.csv" --out "$work/r7.json"
printf 't,q1,q2,q3,q4,q5,q6\n' >"$work/header_only.csv"
expect 3 "no data rows" -- calibrate --robot "$work/header_only.csv" --tracker "$sim/tracker.csv" --out "$work/r8.json"
# A clock relation that cannot be found says why: no valid tracker point, times in another
# unit than the header says, rows closer than the 1 us the times are read to.
awk -F, 'BEGIN { OFS = "," } NR > 1 { $5 = 2 } { print }' "$sim/tracker.csv" >"$work/beam_lost.csv"
expect 3 "clock relation not found: every one of the 1500 tracker points is marked invalid" -- extract --robot "$sim/robot_joints.csv" --tracker "$work/beam_lost.csv"
awk -F, 'BEGIN { OFS = "," } NR > 1 { $1 = sprintf("%.3f", $1 * 1000) } { print }' "$sim/robot_joints.csv" >"$work/robot_ms.csv"
expect 3 "the robot records come 8.0" "is the time column in the unit its header names" -- extract --robot "$work/robot_ms.csv" --tracker "$sim/tracker.csv"
awk -F, 'BEGIN { OFS = "," } NR > 1 { $1 = sprintf("%.9f", NR * 1e-7) } { print }' "$sim/robot_joints.csv" >"$work/robot_fine.csv"
expect 3 "robot rows repeat the time of the row before (times finer than 1 us read as equal)" -- extract --robot "$work/robot_fine.csv" --tracker "$sim/tracker.csv"
# Logs of other tools: a wrong file says what was expected and found; swapped inputs are named.
expect 3 "tracker.cap: contains tracker frames (" -- calibrate --robot "$sim/tracker.cap" --tracker "$sim/robot.cap" --out "$work/r9.json"
expect 3 "--robot and --tracker swapped?" -- calibrate --robot "$sim/tracker.csv" --tracker "$sim/tracker.csv" --out "$work/r9.json"
# A ';' file may use decimal commas (read as they are); a comma-separated one may not, and a
# number with a thousands point and a decimal comma is not guessed at.
printf 'Time [ms];X [mm];Y [mm];Z [mm]\n1500;1.000,5;2;3\n' >"$work/comma.csv"
expect 3 "comma.csv:2: column 'x': not a number: '1.000,5'" -- calibrate --robot "$sim/robot_joints.csv" --tracker "$work/comma.csv" --out "$work/r9.json"
printf 'Time [ms],X [mm],Y [mm],Z [mm]\n1500,1000,5,2,3\n' >"$work/comma2.csv"
expect 3 "a comma used as decimal separator?" -- calibrate --robot "$sim/robot_joints.csv" --tracker "$work/comma2.csv" --out "$work/r9.json"
expect 2 "--columns: 'x:measurement_x' is not C=NAME" -- calibrate --samples "$work/comma.csv" --columns x:measurement_x --out "$work/r9.json"
printf 'Zeit;Achse 1;Achse 2\n1;2;3\n' >"$work/other.csv"
expect 3 "other.csv:1: not a robot joint log: expected t,q1..qN" -- calibrate --robot "$work/other.csv" --tracker "$sim/tracker.csv" --out "$work/r9.json"
no_file "$work/r9.json"
expect 2 "--joint-names needs 6 different comma-separated names, the robot model's joints q1..q6 in order, got 2 ('a,b')" -- calibrate --robot "$sim/robot_joints.csv" --tracker "$sim/tracker.csv" --joint-names a,b --out "$work/r9.json"
expect 2 "--joint-names needs 6 different comma-separated names, the robot model's joints q1..q6 in order" -- calibrate --robot "$sim/robot_joints.csv" --tracker "$sim/tracker.csv" --joint-names a,b,c,d,e,a --out "$work/r9.json"
# A unit in UTF-8 in a header ("[µs]", "(°)") is a text log, not a capture.
{ printf 'time [\302\265s],X [mm],Y [mm],Z [mm]\n'; tail -n +2 "$sim/tracker.csv" | awk -F, -v OFS=, '{ print $1 * 1e6, $2 * 1e3, $3 * 1e3, $4 * 1e3 }'; } >"$work/tracker_us.csv"
if "${run[@]}" calibrate --robot "$sim/robot_joints.csv" --tracker "$work/tracker_us.csv" --method lm --out "$work/r10.json" >/dev/null 2>"$work/r10.err"; then pass; else
  fail "a tracker log with [µs] in its header: $(cat "$work/r10.err")"; fi

# --- units and plausibility (issue 11): the session in degrees and millimetres, no unit in the headers
awk -F, 'NR == 1 { print; next } { printf "%s", $1; for (i = 2; i <= 7; i++) printf ",%.17g", $i * 57.29577951308232; print "" }' \
  "$sim/robot_joints.csv" >"$work/robot_deg.csv"
awk -F, 'NR == 1 { print; next } { printf "%s,%.17g,%.17g,%.17g,%s\n", $1, $2 * 1e3, $3 * 1e3, $4 * 1e3, $5 }' \
  "$sim/tracker.csv" >"$work/tracker_mm.csv"
expect 3 "robot_deg.csv:2: joint q" "looks like degrees: use --angle-unit deg" -- calibrate --robot "$work/robot_deg.csv" --tracker "$sim/tracker.csv" --out "$work/u1.json"
expect 3 "looks like millimetres: use --length-unit mm" -- calibrate --robot "$sim/robot_joints.csv" --tracker "$work/tracker_mm.csv" --out "$work/u1.json"
no_file "$work/u1.json"
if "${run[@]}" calibrate --robot "$work/robot_deg.csv" --tracker "$work/tracker_mm.csv" --method lm --angle-unit deg --length-unit mm \
     --out "$work/u2.json" >/dev/null 2>&1 && [ -s "$work/u2.json" ] &&
   "${run[@]}" extract --robot "$work/robot_deg.csv" --tracker "$work/tracker_mm.csv" --angle-unit deg --length-unit mm \
     --samples "$work/u_samples.csv" >/dev/null && [ "$(wc -l <"$work/u_samples.csv")" -gt 100 ]; then pass; else
  fail "calibrate/extract with --angle-unit deg --length-unit mm"; fi
awk -F, 'NR == 1 { print "t [s],x [mm],y [mm],z [mm],status"; next } { print }' "$work/tracker_mm.csv" >"$work/tracker_mm_header.csv"
expect 3 "column 'x' is in [mm] by its header, but --length-unit m was given" -- calibrate --robot "$sim/robot_joints.csv" --tracker "$work/tracker_mm_header.csv" --length-unit m --out "$work/u3.json"
expect 2 "--length-unit must be 'm' or 'mm', not 'cm'" -- calibrate --samples "$work/s.csv" --length-unit cm
expect 2 "--angle-unit must be 'rad' or 'deg'" -- predict --calibration "$work/result.json" --joints "$work/joints.csv" --angle-unit grad
printf 'q1,q2,q3,q4,q5,q6\n0,-90,90,-90,-90,0\n' >"$work/joints_deg.csv"
expect 3 "joints_deg.csv:2: joint q2 = -90 looks like degrees: use --angle-unit deg" -- predict --calibration "$work/result.json" --joints "$work/joints_deg.csv"
if [ "$("${run[@]}" predict --calibration "$work/result.json" --joints "$work/joints_deg.csv" --angle-unit deg)" = \
     "$("${run[@]}" predict --calibration "$work/result.json" --joints "$work/joints.csv")" ]; then pass; else
  fail "predict --angle-unit deg differs from the same pose in rad"; fi
# Predicted positions in millimetres on request (metres otherwise).
"${run[@]}" predict --calibration "$work/result.json" --joints "$work/joints.csv" --out "$work/p_m.csv" &&
  "${run[@]}" predict --calibration "$work/result.json" --joints "$work/joints.csv" --output-length-unit mm --out "$work/p_mm.csv"
if [ "$(head -1 "$work/p_mm.csv")" = "x [mm],y [mm],z [mm]" ] &&
   paste -d, <(tail -n +2 "$work/p_m.csv") <(tail -n +2 "$work/p_mm.csv") |
     awk -F, '{ for (i = 1; i <= 3; i++) if ((d = $i * 1000 - $(i + 3)) > 1e-9 || d < -1e-9) bad = 1 } END { exit bad || NR != 1 }'; then pass; else
  fail "predict --output-length-unit mm"; fi
expect 2 "--output-length-unit must be 'm' or 'mm', not 'km'" -- predict --calibration "$work/result.json" --joints "$work/joints.csv" --output-length-unit km
printf '[mounting]\ndelta_theta = [0, 0, 0, 0, 0, 0]\ndelta_a = [0, 0.2, -0.1, 0, 0, 0]\ndelta_d = [0, 0, 0, 0, 0, 0]\ndelta_alpha = [0, 0, 0, 0, 0, 0]\n' >"$work/other.conf"
expect 3 "other.conf: its deltas move the tool of the nominal ur5 by up to" "not a calibration of this robot model?" -- \
  calibrate --robot "$sim/robot.cap" --tracker "$sim/tracker.cap" --ur-calibration "$work/other.conf" --out "$work/u4.json"
no_file "$work/u4.json"
# A fit beyond the change bounds: warnings on stderr, the result written all the same, exit 5.
expect 5 "warning: a3 moved" -- calibrate --robot "$sim/robot.cap" --tracker "$sim/tracker.cap" --method lm --max-change-mm 0.001 --out "$work/u5.json"
if [ -s "$work/u5.json" ] && grep -q '"warnings"' "$work/u5.json"; then pass; else fail "exit 5 without its result"; fi
# The nominal model's prior: its kind and tolerances are checked before any work.
expect 2 "--prior must be 'nominal' or 'off', not 'flat'" -- calibrate --samples "$work/s.csv" --prior flat --out "$work/p1.json"
expect 2 "--dh-tolerance-mm must be within (0, 1000) mm, got '0'" -- calibrate --samples "$work/s.csv" --dh-tolerance-mm 0 --out "$work/p1.json"
expect 2 "--tool-tolerance-mm goes with the prior: not with --prior off" -- \
  calibrate --samples "$work/s.csv" --prior off --tool-tolerance-mm 5 --out "$work/p1.json"
no_file "$work/p1.json"

# --- hostile and careless use (issue 13): one check per case -----------------------------------
good_predict=(predict --calibration "$work/result.json" --joints "$work/joints.csv")
# --out /dev/null is refused (it is a device), and /dev/null stays a device (as root too).
expect 4 "is a character device; refusing to replace it" -- "${good_predict[@]}" --out /dev/null
if [ -c /dev/null ]; then pass; else fail "/dev/null is no longer a character device"; fi
# --out through a symlink: the target is replaced, the link is kept.
echo old >"$work/target.csv"
ln -s target.csv "$work/link.csv"
if "${run[@]}" "${good_predict[@]}" --out "$work/link.csv" && [ -L "$work/link.csv" ] &&
   [ "$(head -1 "$work/target.csv")" = "x,y,z" ]; then pass; else fail "--out through a symlink"; fi
# --out onto a FIFO is refused at once (no blocking, no regular file put in its place).
mkfifo "$work/fifo"
err=$(timeout 10 "${run[@]}" "${good_predict[@]}" --out "$work/fifo" 2>&1); code=$?
if [ "$code" -eq 4 ] && grep -q "is a FIFO" <<<"$err" && [ -p "$work/fifo" ]; then pass; else fail "FIFO: exit $code: $err"; fi
# The mode of an existing output is kept.
echo old >"$work/mode.csv"; chmod 640 "$work/mode.csv"
if "${run[@]}" "${good_predict[@]}" --out "$work/mode.csv" && [ "$(stat -c %a "$work/mode.csv")" = 640 ]; then pass; else
  fail "mode not kept: $(stat -c %a "$work/mode.csv")"; fi
# An output that is an input of the run, or another output, is refused before anything is written.
cp "$work/s.csv" "$work/s_copy.csv"
expect 2 "is the same file as the input --samples" -- calibrate --samples "$work/s_copy.csv" --out "$work/s_copy.csv"
if cmp -s "$work/s.csv" "$work/s_copy.csv"; then pass; else fail "--out == --samples changed the input"; fi
expect 2 "is the same file as the input --joints" -- "${good_predict[@]}" --out "$work/./joints.csv"
expect 2 "is the same file as the output --out" -- calibrate --samples "$work/s.csv" --out "$work/same.out" --ur-deltas "$work/same.out"
no_file "$work/same.out"
# stdout on a full device: a non-zero exit and a message, for the result and for printed tables.
if [ -w /dev/full ]; then
  err=$("${run[@]}" "${good_predict[@]}" 2>&1 >/dev/full); code=$?
  if [ "$code" -eq 4 ] && grep -q "stdout: write failed" <<<"$err"; then pass; else fail "predict > /dev/full: exit $code: $err"; fi
  err=$("${run[@]}" calibrate --help 2>&1 >/dev/full); code=$?
  if [ "$code" -eq 4 ]; then pass; else fail "calibrate --help > /dev/full: exit $code"; fi
fi
# Inputs: only regular files (or '-'); /dev/zero is refused at once, not read forever.
err=$(timeout 10 "${run[@]}" calibrate --robot /dev/zero --tracker "$sim/tracker.cap" --out "$work/z.json" 2>&1); code=$?
if [ "$code" -eq 3 ] && grep -q "is a character device, not a regular file" <<<"$err"; then pass; else fail "--robot /dev/zero: exit $code: $err"; fi
no_file "$work/z.json"
expect 3 "is a folder" -- "${good_predict[@]}" --joints "$work" --out "$work/d.csv"
# A NUL byte in a CSV row is an error naming file:line (never a dropped or merged row).
{ head -3 "$work/s.csv"; printf '0,-1.5,1.5,-1.5\000,-1.5,0,1,2,3\n'; tail -n +4 "$work/s.csv"; } >"$work/nul.csv"
expect 3 "nul.csv:4: binary byte 0x00" -- calibrate --samples "$work/nul.csv" --out "$work/n.json"
no_file "$work/n.json"
# A huge field is cut in messages; binary junk is refused by its byte, never echoed raw.
{ echo "q1,q2,q3,q4,q5,q6"; printf '0,0,0,0,0,%s\n' "$(head -c 50000 /dev/zero | tr '\0' 'a')"; } >"$work/huge.csv"
err=$("${run[@]}" "${good_predict[@]/$work\/joints.csv/$work/huge.csv}" --out "$work/h.csv" 2>&1); code=$?
if [ "$code" -eq 3 ] && [ "${#err}" -lt 600 ] && grep -q "\.\.\.\[50000 bytes\]" <<<"$err"; then pass; else
  fail "huge field: exit $code, ${#err} bytes of message"; fi
{ echo "q1,q2,q3,q4,q5,q6"; printf '0,0,0,0,0,\033[31m\001junk\n'; } >"$work/junk.csv"
err=$("${run[@]}" "${good_predict[@]/$work\/joints.csv/$work/junk.csv}" --out "$work/j.csv" 2>&1); code=$?
if [ "$code" -eq 3 ] && grep -qF 'junk.csv:2: binary byte 0x1b' <<<"$err" && ! grep -q $'\033' <<<"$err"; then pass; else
  fail "binary junk not escaped: exit $code: $err"; fi
printf 'q1,q2,q3,q4,q5,q6\n%s\n' "$(head -c 100000 /dev/zero | tr '\0' '1')" >"$work/longline.csv"
expect 3 "longline.csv:2: line longer than" -- "${good_predict[@]/$work\/joints.csv/$work/longline.csv}" --out "$work/l.csv"
# A run that fails while writing the report leaves no result.json (all outputs or none).
mkdir -p "$work/rep/index.html"
expect 4 "index.html': is a folder" -- calibrate --robot "$sim/robot.cap" --tracker "$sim/tracker.cap" --method lm --out "$work/rep.json" --report "$work/rep"
no_file "$work/rep.json"
# record: never truncates an existing capture without --force; opens the ports before any file.
printf 'precious' >"$work/old.cap"
expect 4 "exists; refusing to overwrite a capture (--force replaces it)" -- record --robot-port "$work/no-such-port" --robot-out "$work/old.cap"
expect 3 "no-such-port" -- record --robot-port "$work/no-such-port" --robot-out "$work/old.cap" --force
if [ "$(cat "$work/old.cap")" = precious ]; then pass; else fail "record touched an existing capture"; fi
expect 3 "no-such-port" -- record --robot-port "$work/no-such-port" --robot-out "$work/new.cap"
no_file "$work/new.cap"
expect 2 "is the same file as the output --robot-out" -- record --robot-port "$work/p1" --tracker-port "$work/p2" --robot-out "$work/both.cap" --tracker-out "$work/both.cap"
expect 2 "is the same file as the input --robot-port" -- record --robot-port "$work/p1" --robot-out "$work/p1"
expect 3 "--rtde '127.0.0.1:1': Connection refused" -- record --rtde 127.0.0.1:1 --robot-out "$work/rtde.txt"
no_file "$work/rtde.txt"
expect 2 "--rtde must be HOST, HOST:PORT, an IPv6 address or [IPv6]:PORT (PORT 1 .. 65535), not 'ur5:99999'" -- record --rtde ur5:99999
expect 2 "--rtde records the robot alone" -- record --rtde 127.0.0.1 --tracker-port "$work/p2"
expect 2 "--duration-s must be within [0, 1e+09] s (0: until Ctrl-C / SIGTERM)" -- record --robot-port "$work/p1" --duration-s -1
expect 2 "--duration-s must be a number within [0, 1e+09] s (0: until Ctrl-C / SIGTERM), got 'nan'" -- record --robot-port "$work/p1" --duration-s nan

# --- progress: on stderr when it is a terminal (script(1) gives one), never in a pipe or with --quiet
if command -v script >/dev/null; then
  # LM alone: the progress lines are the same code for every stage, and the population stage
  # would add seconds under qemu.
  tty_cmd="$(printf '%q ' "${run[@]}") calibrate --robot $sim/robot.cap --tracker $sim/tracker.cap --method lm --out $work/tty.json"
  script -qec "$tty_cmd" /dev/null >"$work/tty.out" 2>&1
  script -qec "$tty_cmd --quiet" /dev/null >"$work/tty_quiet.out" 2>&1
  if grep -q "decode\] pass 2/2 (samples): 100 %" "$work/tty.out" && grep -q "\[LM\] iteration" "$work/tty.out" &&
     ! grep -q "\[decode\]\|\[LM\]" "$work/tty_quiet.out" "$work/cap.out"; then
    pass
  else
    fail "progress on a terminal only"
  fi
fi

# --- an input is never an output, whichever option names it: refused, the input untouched
ur_result_json ur5 0.089159 -0.425 -0.39225 0.10915 0.09465 0.0823 "0, 0, 0" \
  "[[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]" >"$work/model.json"
cp "$work/model.json" "$work/model.orig"
{ echo "q1,q2,q3,q4,q5,q6,x,y,z"; tail -n +2 "$sim/truth_samples.csv" | cut -d, -f4-12; } >"$work/paired.csv"
expect 2 "is the same file as the input --robot-model" -- calibrate --samples "$work/paired.csv" --robot-model "$work/model.json" --out "$work/model.json"
expect 2 "is the same file as the input --robot-model" -- plan --robot-model "$work/model.json" --count 12 --tracker-position 2,0.5,0.6 --out "$work/model.json"
mkdir -p "$work/simdir"
cp "$work/model.json" "$work/simdir/truth.json"
expect 2 "is the same file as the input --robot-model" -- simulate --robot-model "$work/simdir/truth.json" --out-dir "$work/simdir" --waypoints 4 --duration-s 30 --force
# simulate never replaces an earlier session (a real recording may sit there) without --force.
mkdir -p "$work/rec"
printf 'recorded' >"$work/rec/robot.cap"
expect 4 "already holds robot.cap; refusing to overwrite a session (--force replaces it)" -- simulate --out-dir "$work/rec" --waypoints 4 --duration-s 30
if [ "$(cat "$work/rec/robot.cap")" = recorded ] && [ ! -e "$work/rec/truth.json" ]; then pass; else
  fail "simulate overwrote a capture or wrote beside it without --force"; fi
expect 0 "" -- simulate --out-dir "$work/rec" --waypoints 4 --duration-s 30 --force
if cmp -s "$work/model.json" "$work/model.orig" && cmp -s "$work/simdir/truth.json" "$work/model.orig"; then pass; else
  fail "an input given as an output was overwritten"; fi

# --- numbers: each option range-checked with its name, no silent rounding or truncation
expect 2 "--seed must be a whole number" -- calibrate --samples "$work/paired.csv" --seed 1.5 --out "$work/n1.json"
expect 2 "--seed must be a whole number" -- calibrate --samples "$work/paired.csv" --seed 18446744073709551616 --out "$work/n1.json"
expect 2 "--seed must be a whole number" -- plan --robot-model ur5 --count 12 --tracker-position 2,0.5,0.6 --seed -1 --out "$work/n1.csv"
expect 2 "--poses must be a whole number" -- validate --calibration "$work/model.json" --truth "$work/model.json" --poses 1.5
expect 2 "--tool must be X,Y,Z in metres, each within [-10, 10] m" -- calibrate --samples "$work/paired.csv" --tool 0,0,nan --out "$work/n1.json"
expect 2 "training pose(s) of" -- calibrate --samples "$work/paired.csv" --split 0.01 --out "$work/n1.json"
expect 2 "--split must be within (0, 1] (the training share), got '0'" -- calibrate --samples "$work/paired.csv" --split 0 --out "$work/n1.json"
expect 2 "--drift-ppm must be a number within [-1000, 1000], got 'nan'" -- simulate --out-dir "$work/n2" --drift-ppm nan
expect 2 "--waypoints must be within [2, 2000]" -- simulate --out-dir "$work/n2" --waypoints 100000
no_file "$work/n1.json"
if "${run[@]}" calibrate --samples "$work/paired.csv" --method lm --split 1 --seed 9007199254740993 --out "$work/n3.json" >/dev/null 2>&1 &&
   grep -q '"seed": 9007199254740993' "$work/n3.json"; then pass; else fail "--seed 2^53+1 not kept exactly in result.json"; fi

# --- model fields beyond any robot are refused by name, not predicted as NaN
ur_result_json ur5 1e300 -0.425 -0.39225 0.10915 0.09465 0.0823 "0, 0, 0" \
  "[[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]" >"$work/huge_d.json"
expect 3 'huge_d.json: "dh"[0].d = 1.0000000000000001e+300 m is beyond 1000 m: not a robot' -- predict --calibration "$work/huge_d.json" --joints "$work/joints.csv" --out "$work/n4.csv"
sed 's/"theta_offset": 0.0, "d": 0.0, "a": -0.425/"theta_offset": 1e20, "d": 0.0, "a": -0.425/' "$work/model.json" >"$work/huge_theta.json"
expect 3 '"dh"[1].theta_offset = 1e+20 rad is beyond' -- predict --calibration "$work/huge_theta.json" --joints "$work/joints.csv" --out "$work/n4.csv"
no_file "$work/n4.csv"
# A base 1e300 m from the tracker was predicted, exported and scored "MAE inf" with exit 0.
ur_result_json ur5 0.089159 -0.425 -0.39225 0.10915 0.09465 0.0823 "0, 0, 0" \
  "[[1, 0, 0, 1e300], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]" >"$work/far_base.json"
far='far_base.json: "base_to_tracker" puts the robot'"'"'s base 1.0000000000000001e+300 m from the tracker, beyond 100 m: not a tracker'"'"'s frame'
expect 3 "$far" -- predict --calibration "$work/far_base.json" --joints "$work/joints.csv" --out "$work/n4.csv"
expect 3 "$far" -- export --calibration "$work/far_base.json" --out "$work/n4.urdf"
expect 3 "$far" -- validate --calibration "$work/far_base.json" --truth "$work/model.json"
no_file "$work/n4.csv"
no_file "$work/n4.urdf"

expect 2 "--robot-port and --tracker-port name the same port" -- record --robot-port "$work/model.json" --tracker-port "$work/model.json" --robot-out "$work/rec1.cap" --tracker-out "$work/rec2.cap"
expect 2 "--calibration and --joints both read stdin" -- predict --calibration - --joints - --out "$work/n6.csv"

# --- stdout: a closed pipe is an output error (exit 4), and a file on stdout keeps the tables off it
# (20,000 predictions: more than a pipe holds, so the writer meets the closed end every time)
awk 'BEGIN { print "q1,q2,q3,q4,q5,q6"; for (i = 0; i < 20000; ++i) printf "%.6f,-1,1,0,0.5,%.6f\n", i * 1e-4, i * 2e-4 }' >"$work/many.csv"
{ "${run[@]}" predict --calibration "$work/model.json" --joints "$work/many.csv" --out - 2>"$work/pipe.err"; echo $? >"$work/pipe.code"; } | true
if [ "$(cat "$work/pipe.code")" = 4 ] && grep -q "hivecal predict:" "$work/pipe.err"; then pass; else
  fail "predict into a closed pipe: exit $(cat "$work/pipe.code") ($(cat "$work/pipe.err")), want 4 with a message"; fi
"${run[@]}" calibrate --samples "$work/paired.csv" --method lm --ur-deltas - --out "$work/n5.json" >"$work/deltas.out" 2>/dev/null
if grep -q '^\[mounting\]' "$work/deltas.out" && ! grep -q "Table 1" "$work/deltas.out"; then pass; else
  fail "--ur-deltas -: stdout holds more than the deltas"; fi

# --- a capture cut to its first stops calibrates, but the job says the poses do not span the
# model (exit 5, the result written): its test samples stand at the training poses.
head -c $(($(stat -c %s "$sim/robot.cap") * 30 / 100)) "$sim/robot.cap" >"$work/cut.cap"
expect 5 "stand at only 2 distinct poses (6 coordinates) for the" "the poses do not span the model" -- \
  calibrate --robot "$work/cut.cap" --tracker "$sim/tracker.cap" --out "$work/cut.json"
if [ -s "$work/cut.json" ]; then pass; else fail "no result written for the cut capture"; fi

# --- a signal ends a command cleanly: no temporary left, the shell sees the signal (128 + N)
# (an hour of session at most: seconds of writing, so the signal comes while temporaries exist)
# interrupted SIGNAL DIR: a long simulate into DIR, sent SIGNAL after a second; its exit code.
interrupted() {
  "${run[@]}" simulate --out-dir "$2" --waypoints 2000 --duration-s 3600 >/dev/null 2>&1 &
  local pid=$!
  sleep 1
  kill "-$1" "$pid"
  wait "$pid" 2>/dev/null
}
# ends_cleanly SIGNAL CODE DIR: interrupted exits with CODE and leaves DIR as it was: absent
# without a temporary beside it, or empty.
ends_cleanly() {
  local code
  interrupted "$1" "$3"
  code=$?
  if [ "$code" = "$2" ] && { { [ -d "$3" ] && [ -z "$(ls -A "$3")" ]; } ||
       { [ ! -e "$3" ] && ! compgen -G "$3.tmp.*" >/dev/null; }; }; then pass; else
    fail "simulate after SIG$1: exit $code (want $2), left: $(ls -A "$3" "$(dirname "$3")" 2>&1)"; fi
}
ends_cleanly INT 130 "$work/sig/new"
mkdir -p "$work/sig/old"
ends_cleanly TERM 143 "$work/sig/old"
# simulate --serve whose reader left (its writes wait for room that never comes): SIGTERM
# still ends it within seconds, with its stats line.
"${run[@]}" simulate --serve --speed 0 --serve-delay-s 0.5 --out-dir "$work/sig/serve" --waypoints 4 --duration-s 30 \
  >"$work/serve.log" 2>&1 &
pid=$!
for _ in $(seq 1 50); do grep -q '^tracker ' "$work/serve.log" 2>/dev/null && break; sleep 0.1; done
robot_pty=$(awk '$1 == "robot" { print $2 }' "$work/serve.log")
[ -n "$robot_pty" ] && timeout 5 head -c 100 "$robot_pty" >/dev/null
sleep 1.5
# stops_on_term PID LOG WHEN: SIGTERM ends the server PID within 5 s, its stats line in LOG.
stops_on_term() {
  kill -TERM "$1"
  for _ in $(seq 1 50); do kill -0 "$1" 2>/dev/null || break; sleep 0.1; done
  if kill -0 "$1" 2>/dev/null; then
    kill -KILL "$1"
    fail "simulate --serve ignored SIGTERM $3"
  elif wait "$1" && grep -q '^served ' "$2"; then pass; else
    fail "simulate --serve after SIGTERM $3: $(cat "$2")"; fi
}
stops_on_term "$pid" "$work/serve.log" "after its reader left"

# --- issue 54: outputs named twice, concurrent runs, more signals, simulate's numbers
# An output that is a file another output writes is refused before any input is read (the
# report's page replaced the result): joints.csv is no samples file, yet the refusal comes first.
mkdir -p "$work/rp"
expect 2 "--report '$work/rp' writes '$work/rp/index.html', which is the same file as the output --out '$work/rp/index.html'" -- \
  calibrate --samples "$work/joints.csv" --out "$work/rp/index.html" --report "$work/rp"
expect 2 "writes '$work/rp/./index.html', which is the same file as the output --ur-deltas" -- \
  calibrate --samples "$work/joints.csv" --out "$work/rp.json" --ur-deltas "$work/rp/index.html" --report "$work/rp/."
no_file "$work/rp/index.html"
expect 2 "--out: '  ' is blank: give a file name" -- predict --calibration "$work/result.json" --joints "$work/joints.csv" --out "  "
expect 2 "--report: ' ' is blank: give a folder path" -- calibrate --samples "$work/joints.csv" --out "$work/b.json" --report " "
# stdout on a full device: the tables printed before the commit go first, and when they do
# not arrive no output is replaced; a failure after the commit names the outputs written.
if [ -w /dev/full ]; then
  echo old >"$work/full.json"
  err=$("${run[@]}" calibrate --samples "$work/paired.csv" --method lm --split 1 --out "$work/full.json" 2>&1 >/dev/full); code=$?
  if [ "$code" -eq 4 ] && grep -qF "stdout: write failed: No space left on device; no output was replaced" <<<"$err" &&
     [ "$(cat "$work/full.json")" = old ]; then pass; else fail "calibrate > /dev/full: exit $code: $err"; fi
  err=$("${run[@]}" report --calibration "$work/cap.json" --out "$work/fullrep" 2>&1 >/dev/full); code=$?
  if [ "$code" -eq 4 ] && grep -qF "stdout: write failed: No space left on device; the outputs were written before it: --out '$work/fullrep'" <<<"$err" &&
     [ -s "$work/fullrep/index.html" ]; then pass; else fail "report --out DIR > /dev/full: exit $code: $err"; fi
fi
# One folder named several ways (absolute and relative, sub/..) is locked once: the commit
# waited for its own lock forever.
mkdir -p "$work/h1/x/sub"
if (cd "$work/h1/x" && timeout 120 "${run[@]}" calibrate --samples "$work/paired.csv" --method lm --split 1 \
      --out "$work/h1/x/result.json" --ur-deltas sub/../d.conf --report report >/dev/null 2>&1) &&
   [ -s "$work/h1/x/result.json" ] && [ -s "$work/h1/x/d.conf" ] && [ -s "$work/h1/x/report/index.html" ]; then pass; else
  fail "calibrate with one folder named two ways: $(ls -A "$work/h1/x")"; fi
# Six runs creating one report folder at once: each writes it whole (five failed with
# "Directory not empty").
mkdir -p "$work/m7"
pids=()
for i in 1 2 3 4 5 6; do
  "${run[@]}" report --calibration "$work/cap.json" --out "$work/m7/report" >"$work/m7.$i.log" 2>&1 &
  pids+=($!)
done
m7_failed=0
for pid in "${pids[@]}"; do wait "$pid" || m7_failed=$((m7_failed + 1)); done
if [ "$m7_failed" = 0 ] && cmp -s "$work/m7/report/index.html" "$work/redrawn/index.html" &&
   [ "$(ls -A "$work/m7")" = report ] && [ "$(ls -A "$work/m7/report")" = index.html ]; then pass; else
  fail "six concurrent reports into one new folder: $m7_failed failed: $(cat "$work"/m7.*.log) $(ls -A "$work/m7" "$work/m7/report")"; fi
# SIGUSR1 and SIGALRM end a run as SIGTERM does, its temporaries removed; a file size limit
# (SIGXFSZ) is an output error, exit 4, nothing left.
ends_cleanly USR1 138 "$work/sig/usr1"
mkdir -p "$work/sig/alrm"
ends_cleanly ALRM 142 "$work/sig/alrm"
mkdir -p "$work/sig/xfsz"
code=$( (ulimit -f 200; "${run[@]}" simulate --out-dir "$work/sig/xfsz" --waypoints 40 --duration-s 300 >/dev/null 2>"$work/xfsz.err"); echo $?)
if [ "$code" = 4 ] && grep -q "write failed: File too large" "$work/xfsz.err" && [ -z "$(ls -A "$work/sig/xfsz")" ]; then pass; else
  fail "simulate over ulimit -f: exit $code (want 4), $(cat "$work/xfsz.err"), left: $(ls -A "$work/sig/xfsz")"; fi
# simulate refuses a pacing or a delay it could not keep (NaN, 1e-9, 1e9, negative) and
# every simulated error that is not finite, before writing anything.
# (each under `timeout`: such a value, once accepted, served for ever)
refused_serve() {  # refused_serve MESSAGE OPTIONS...: exit 2 and MESSAGE at once
  local message=$1 err code
  shift
  err=$(timeout 20 "${run[@]}" simulate --serve --out-dir "$work/h2" --waypoints 4 --duration-s 30 "$@" 2>&1 >/dev/null); code=$?
  if [ "$code" = 2 ] && grep -qF -- "$message" <<<"$err"; then pass; else fail "simulate --serve $*: exit $code (want 2): $err"; fi
}
refused_serve "--speed must be a number, got 'nan': not a number" --speed nan
for speed in 1e-9 -1 1e9; do
  refused_serve "--speed must be 0 (as fast as read) or within [0.01, 10000] session seconds per second, got '$speed'" --speed "$speed"
done
for delay in nan 1e9 -1; do
  refused_serve "--serve-delay-s must be" --serve-delay-s "$delay"
  refused_serve "within [0, 3600], got '$delay'" --serve-delay-s "$delay"
done
expect 2 "--compliance-urad J2,J3: J2 must be a number within [-10000, 10000] urad, got 'nan': not a number" -- simulate --compliance-urad nan,0 --out-dir "$work/h2"
expect 2 "--compliance-urad J2,J3: J2 must be within [-10000, 10000] urad, got '1e300'" -- simulate --compliance-urad 1e300,0 --out-dir "$work/h2"
expect 2 "--harmonic-urad J,K,S,C: S must be a number within [-10000, 10000] urad, got 'nan'" -- simulate --harmonic-urad 3,1,nan,0 --out-dir "$work/h2"
expect 2 "--length-sigma-um must be within [0, 100000], got 'inf'" -- simulate --length-sigma-um inf --out-dir "$work/h2"
expect 2 "--angle-sigma-urad must be within [0, 100000], got '1e9'" -- simulate --angle-sigma-urad 1e9 --out-dir "$work/h2"
no_file "$work/h2"
# A stop request ends the wait before streaming at once (it slept through SIGTERM).
"${run[@]}" simulate --serve --serve-delay-s 600 --out-dir "$work/sig/delay" --waypoints 4 --duration-s 30 >"$work/delay.log" 2>&1 &
pid=$!
for _ in $(seq 1 50); do grep -q '^tracker ' "$work/delay.log" 2>/dev/null && break; sleep 0.1; done
stops_on_term "$pid" "$work/delay.log" "in its --serve-delay-s"

expect 2 "--orientation-form must be rotation-vector or euler-xyz, not 'zyx'" -- calibrate --samples "$work/paired.csv" --orientation-form zyx --out "$work/o.json"
expect 2 "is not C=NAME or C=NAME[unit] with C one of" -- calibrate --samples "$work/paired.csv" --columns "w=measurement_w" --out "$work/o.json"
printf 'q1,q2,q3,q4,q5,q6,px [mm],y,z\n0,0,0,0,0,0,1,2,3\n' >"$work/conflict.csv"
expect 3 "column 'px' is in [mm] by its header, but --columns gives [m]" -- calibrate --samples "$work/conflict.csv" --columns "x=px[m]" --out "$work/o.json"

# --- iso9283: three poses reached four times each, on a 20 um square around the commanded point
# shifted by (30, -40, 0) um: AP_P 0.0500 mm and RP_l = sqrt(2) 10 um = 0.0141 mm for each
printf 'q1,q2,q3,q4,q5,q6\n0.1,-1.2,1.3,-0.4,0.8,0.2\n-0.5,-1.0,1.6,-0.9,1.2,0.4\n0.9,-1.7,1.1,0.3,0.5,-0.6\n' >"$work/iso_poses.csv"
"${run[@]}" predict --calibration "$work/model.json" --joints "$work/iso_poses.csv" --out "$work/iso_cmd.csv" 2>/dev/null
paste -d, "$work/iso_poses.csv" "$work/iso_cmd.csv" | awk -F, 'NR == 1 { print "q1,q2,q3,q4,q5,q6,x,y,z"; next }
  { for (r = 0; r < 4; ++r) { dx = (r == 0 || r == 3) ? 10e-6 : -10e-6; dy = (r < 2) ? 10e-6 : -10e-6
      printf "%s,%s,%s,%s,%s,%s,%.9f,%.9f,%.9f\n", $1, $2, $3, $4, $5, $6, $7 + 30e-6 + dx, $8 - 40e-6 + dy, $9 } }' >"$work/iso_reaches.csv"
if "${run[@]}" iso9283 --samples "$work/iso_reaches.csv" --calibration "$work/model.json" --out "$work/iso.csv" --report "$work/iso.html" >"$work/iso.txt" 2>&1 &&
   grep -q "<tr><td>2</td><td>6</td><td>1</td><td>4</td><td>0.0500</td>" "$work/iso.html" &&
   [ "$(grep -c ',4,0.0500,0.0300,-0.0400,0.0000,0.0141$' "$work/iso.csv")" -eq 3 ] &&
   grep -q "3 poses with repeated reaches (0 with one reach, left out); worst AP_P 0.0500 mm, worst RP_l 0.0141 mm" "$work/iso.txt"; then pass; else
  fail "iso9283: $(cat "$work/iso.txt" "$work/iso.csv")"; fi
paste -d, "$work/iso_poses.csv" "$work/iso_cmd.csv" | sed '1s/.*/q1,q2,q3,q4,q5,q6,x,y,z/' >"$work/iso_once.csv"
expect 3 "no pose was reached twice" -- iso9283 --samples "$work/iso_once.csv" --calibration "$work/model.json"
expect 2 "give --calibration or --robot-model, not both" -- iso9283 --samples "$work/iso_reaches.csv" --calibration "$work/model.json" --robot-model ur5

# --- export: a result as URDF (a tcp and the tracker frame), a nominal arm as a robot
# description that reads back; one source only (tests/apps/test_urdf_export.cpp checks the FK)
if "${run[@]}" export --calibration "$work/model.json" --out "$work/arm.urdf" 2>/dev/null &&
   grep -q '<joint name="joint_6" type="revolute">' "$work/arm.urdf" && grep -q '<link name="tracker"/>' "$work/arm.urdf"; then pass; else
  fail "export --calibration --format urdf"; fi
if "${run[@]}" export --robot-model ur10e --format robot-json --out "$work/ur10e.json" 2>/dev/null &&
   "${run[@]}" export --robot-model "$work/ur10e.json" --out "$work/ur10e.urdf" 2>/dev/null &&
   ! grep -q '<link name="tracker"/>' "$work/ur10e.urdf"; then pass; else
  fail "export --format robot-json, read back by --robot-model"; fi
if "${run[@]}" export --robot-model ur5e --format ur-kinematics --ur-hash calib_42 --out "$work/ur5e.yaml" 2>/dev/null &&
   grep -q '^  wrist_3:$' "$work/ur5e.yaml" && grep -q '^  hash: calib_42$' "$work/ur5e.yaml"; then pass; else
  fail "export --format ur-kinematics"; fi
expect 0 "hash calib_hivecal_" -- export --robot-model ur5e --format ur-kinematics --out "$work/ur5e-own.yaml"
expect 2 "--ur-hash must be letters, digits and '_'" -- export --robot-model ur5e --format ur-kinematics --ur-hash 'a b'
expect 2 "--ur-hash goes with --format ur-kinematics: a urdf has no calibration hash" -- export --robot-model ur5e --ur-hash calib_42 --out "$work/hash.urdf"
no_file "$work/hash.urdf"
# A URDF is a robot model (--robot-model FILE.urdf): predict checks it against the built-in
# table, calibrate starts from it.
"${run[@]}" export --robot-model ur5 --out "$work/ur5.urdf" 2>/dev/null
"${run[@]}" predict --robot-model "$work/ur5.urdf" --joints "$work/many.csv" --out "$work/from_urdf.csv" 2>/dev/null
"${run[@]}" predict --robot-model ur5 --joints "$work/many.csv" --out "$work/from_table.csv" 2>/dev/null
if [ -s "$work/from_urdf.csv" ] && paste -d, "$work/from_urdf.csv" "$work/from_table.csv" | awk -F, 'NR > 1 {
     for (i = 1; i <= 3; ++i) { d = $i - $(i + 3); if (d < 0) d = -d; if (d > 1e-9) bad = 1 } } END { exit bad }'; then pass; else
  fail "predict --robot-model ur5.urdf differs from the built-in ur5"; fi
expect 2 "--robot-model has no tracker frame" -- predict --robot-model ur5 --joints "$work/joints.csv" --frame tracker
if "${run[@]}" calibrate --samples "$work/paired.csv" --robot-model "$work/ur5.urdf" --method lm --split 1 --out "$work/from_urdf.json" >/dev/null 2>&1 &&
   grep -q '"robot": "ur5"' "$work/from_urdf.json"; then pass; else fail "calibrate --robot-model ur5.urdf"; fi
# check-robot: the table, tools, limits and FK of a robot file (or a built-in table), or the
# file refused by line.
if "${run[@]}" check-robot "$work/ur5.urdf" >"$work/check.txt" 2>&1 && grep -q "^convention: standard-dh$" "$work/check.txt" &&
   grep -q "2            0.000000         0.0000       -425.0000         0.000000" "$work/check.txt" &&
   grep -q "FK at q = 0 (q \[deg\] 0.000 0.000 0.000 0.000 0.000 0.000): tool 1 at -817.2500, -191.4500, -5.4910 mm" "$work/check.txt"; then pass; else
  fail "check-robot ur5.urdf: $(cat "$work/check.txt")"; fi
if "${run[@]}" check-robot ur10e --joints "$work/joints.csv" | grep -q "^FK at pose 1 (q \[deg\] 0.000 -90.000 90.000 -90.000 -90.000 0.000)"; then pass; else
  fail "check-robot --joints"; fi
# A robot's name is the file's text: its control bytes (a window title, a clear screen, a NUL that
# ended the printout) reach no terminal and no report raw; every printed name is escaped as
# messages are (port::printable).
only_text() {  # FILE: holds no control byte but newline, tab and CR (UTF-8 bytes allowed)
  [ -s "$1" ] && [ "$(LC_ALL=C tr -d '\n\t\r\040-\176\200-\377' <"$1" | wc -c)" -eq 0 ]
}
ur_result_json '\u001b]0;pwned\u0007\u001b[2J\u0000tail' 0.089159 -0.425 -0.39225 0.10915 0.09465 0.0823 "0.0, 0.0, 0.1" \
  "[[1, 0, 0, 1], [0, 1, 0, 2], [0, 0, 1, 3], [0, 0, 0, 1]]" >"$work/hostile.json"
if "${run[@]}" check-robot "$work/hostile.json" >"$work/hostile.txt" 2>&1 && only_text "$work/hostile.txt" &&
   grep -qF 'robot: \x1b]0;pwned\x07\x1b[2J\x00tail (file ' "$work/hostile.txt" && grep -q "^convention: standard-dh$" "$work/hostile.txt"; then pass; else
  fail "check-robot of a name with control bytes: $(od -c "$work/hostile.txt" | head -5)"; fi
if "${run[@]}" calibrate --samples "$work/paired.csv" --robot-model "$work/hostile.json" --method lm --split 1 --out "$work/hostile_result.json" \
     --report "$work/hostile_report" >/dev/null 2>&1 && only_text "$work/hostile_report/index.html" &&
   grep -qF '<title>hivecal calibration: \x1b]0;pwned\x07\x1b[2J\x00tail</title>' "$work/hostile_report/index.html"; then pass; else
  fail "calibrate --report of a name with control bytes"; fi
# ... nor does any other command that prints it: a registration of that result, plan's clamped
# limits (the description's own range named by its name), iso9283's command frame.
sed 's/^  "tool": /  "joint_limits": [[-1, 1], [-1, 1], [-1, 1], [-1, 1], [-1, 1], [-1, 1]],\n  "tool": /' "$work/hostile.json" \
  >"$work/hostile_limits.json"
printf 'lower,upper\n-2,2\n-2,2\n-2,2\n-2,2\n-2,2\n-2,2\n' >"$work/wider.csv"
{ "${run[@]}" calibrate --fit base --robot-model "$work/hostile_result.json" --samples "$work/paired.csv" --out "$work/hostile_reg.json"
  "${run[@]}" plan --robot-model "$work/hostile_limits.json" --joint-limits "$work/wider.csv" --count 4 --tracker-position 2,0.5,0.6 \
    --candidates 64 --restarts 1 --refine 0 --out "$work/hostile_plan.csv"
  "${run[@]}" iso9283 --samples "$work/paired.csv" --robot-model "$work/hostile.json" --out "$work/hostile_iso.csv"
} >"$work/hostile_more.txt" 2>&1
if only_text "$work/hostile_more.txt" && grep -qF 'registering '"$work"'/hostile_result.json (\x1b]0;pwned' "$work/hostile_more.txt" &&
   grep -qF "goes beyond the \x1b]0;pwned" "$work/hostile_more.txt" &&
   grep -qF "commanded positions from the nominal \x1b]0;pwned" "$work/hostile_more.txt"; then pass; else
  fail "registration, plan, iso9283 of a name with control bytes: $(od -c "$work/hostile_more.txt" | grep -m3 033)"; fi
sed 's/"title": "hivecal calibration: ur5"/"title": "\\u001b]0;pwned\\u0007"/' "$work/cap.json" >"$work/hostile_title.json"
if grep -q 'u001b' "$work/hostile_title.json" && "${run[@]}" report --calibration "$work/hostile_title.json" --out "$work/hostile_redrawn" >/dev/null &&
   only_text "$work/hostile_redrawn/index.html" && grep -qF '<title>\x1b]0;pwned\x07</title>' "$work/hostile_redrawn/index.html"; then pass; else
  fail "report of a result whose title holds control bytes"; fi
# A samples file named with control bytes: its name reaches neither the terminal nor the page raw
# (the input line, the report's every text, validate's line), each through port::printable.
hostile_csv="$work/"$'pa\x1b]0;evil\x07ired.csv'
cp "$work/paired.csv" "$hostile_csv"
if "${run[@]}" calibrate --samples "$hostile_csv" --method lm --split 1 --out "$work/hn.json" --report "$work/hn_report" \
     >"$work/hn.txt" 2>&1 &&
   "${run[@]}" validate --calibration "$work/hn.json" --samples "$hostile_csv" --out "$work/hn_v.json" >>"$work/hn.txt" 2>&1 &&
   only_text "$work/hn.txt" && only_text "$work/hn_report/index.html" &&
   grep -qF "input: $work/pa\x1b]0;evil\x07ired.csv (" "$work/hn.txt" &&
   grep -qF "validation on $work/pa\x1b]0;evil\x07ired.csv: " "$work/hn.txt" &&
   grep -qF "<li>input: $work/pa\x1b]0;evil\x07ired.csv (" "$work/hn_report/index.html"; then pass; else
  fail "a samples file named with control bytes: $(od -c "$work/hn.txt" | head -5)"; fi
printf '<robot name="r">\n<joint name="j" type="floating"><parent link="a"/><child link="b"/></joint>\n</robot>\n' >"$work/free.urdf"
expect 3 "free.urdf:2: joint 'j' is 'floating' (a free body" -- predict --robot-model "$work/free.urdf" --joints "$work/joints.csv"
expect 3 "free.urdf:2: joint 'j' is 'floating' (a free body" -- check-robot "$work/free.urdf"
expect 2 "give either --calibration (a result) or --robot-model" -- export --calibration "$work/model.json" --robot-model ur5
expect 2 "--format must be urdf, ur-kinematics or robot-json, not 'sdf'" -- export --robot-model ur5 --format sdf
expect 2 "is the same file as the input --calibration" -- export --calibration "$work/model.json" --out "$work/model.json"

# --- every command has --help
for cmd in calibrate validate predict plan simulate record extract demo report export check-robot iso9283; do
  if "${run[@]}" "$cmd" --help | grep -q "usage: hivecal $cmd"; then pass; else
    fail "$cmd --help"; fi
done

finish
