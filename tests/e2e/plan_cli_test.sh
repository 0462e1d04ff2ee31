#!/usr/bin/env bash
# `hivecal plan` end to end: bad options and inputs give a clear message, the documented exit
# code and no output file; a good run writes the joints CSV (readable by `predict`) and the
# URScript, the same bytes for a seed; the tool-down report names what freeing the
# orientation gains.
#   plan_cli_test.sh <hivecal binary> [emulator words...]
set -u
source "$(dirname "$0")/cli_lib.sh" "$@"

# expect_plan CODE SUBSTRING -- ARGS...: expect for `hivecal plan ARGS`, and no output left
# at $work/out.csv (removed if there is one, so the next check starts clean).
expect_plan() {
  local code=$1 pattern=$2
  shift 3
  expect "$code" "$pattern" -- plan "$@"
  no_file "$work/out.csv"
  rm -f "$work/out.csv"
}

cell=(--robot-model ur5e --tracker-position 2,0.5,0.6 --tool 0,0,0.05 --candidates 256)
out=(--out "$work/out.csv")
# One exchange run and no refinement where a check reads the report, the constraints or the
# bytes, not the plan's quality (one run keeps the defaults; lib/plan tests the method and the
# planner's golden digest plans with the defaults): each such run takes a third of the time.
quick=(--restarts 1 --refine 0)

# --- usage errors (exit 2)
expect_plan 2 "--count, --tracker-position and --out are required" -- --count 10
expect_plan 2 "--count must be within [1, 128]" -- "${cell[@]}" "${out[@]}" --count 0
expect_plan 2 "--count must be a whole number" -- "${cell[@]}" "${out[@]}" --count 2.5
expect_plan 2 "--dwell must be within [0.3" -- "${cell[@]}" "${out[@]}" --count 10 --dwell 0.1
expect_plan 2 "--objective must be d-optimal" -- "${cell[@]}" "${out[@]}" --count 10 --objective a-optimal
expect_plan 2 "--restarts must be within [1, 64]" -- "${cell[@]}" "${out[@]}" --count 10 --restarts 0
expect_plan 2 "--refine must be within [0, 16]" -- "${cell[@]}" "${out[@]}" --count 10 --refine 17
expect_plan 2 "--prior-mm must be within [0, 1000]" -- "${cell[@]}" "${out[@]}" --count 10 --prior-mm -1
expect_plan 2 "--params must be 'full' or 'paper'" -- "${cell[@]}" "${out[@]}" --count 10 --params all
expect_plan 2 "unknown robot model 'ur7'" -- "${cell[@]}" "${out[@]}" --count 10 --robot-model ur7
expect_plan 2 "--tracker-position must be X,Y,Z" -- "${cell[@]}" "${out[@]}" --count 10 --tracker-position 1,2
expect_plan 2 "--acceptance-deg must be a number within [1, 180], got 'wide': not a number" -- "${cell[@]}" "${out[@]}" --count 10 --acceptance-deg wide
expect_plan 2 "--candidates must be at least --count" -- "${cell[@]}" "${out[@]}" --count 20 --candidates 10
# --- bad inputs (exit 3)
expect_plan 3 "cannot open" -- "${cell[@]}" "${out[@]}" --count 10 --joint-limits "$work/missing.csv"
printf 'min,max\n-1,1\n' >"$work/badlimits.csv"
expect_plan 3 "unexpected header" -- "${cell[@]}" "${out[@]}" --count 10 --joint-limits "$work/badlimits.csv"
printf 'lower,upper\n-1,1\n-1,1\n-1,1\n-1,1\n-1,1\n' >"$work/fivelimits.csv"
expect_plan 3 "5 rows, expected 6 (one per joint: the robot model has 6 joints)" -- "${cell[@]}" "${out[@]}" --count 10 --joint-limits "$work/fivelimits.csv"
printf 'lower,upper\n-1,1\n-1,1\n1,-1\n-1,1\n-1,1\n-1,1\n' >"$work/swapped.csv"
expect_plan 3 "lower limit not below the upper one" -- "${cell[@]}" "${out[@]}" --count 10 --joint-limits "$work/swapped.csv"
# --- nothing meets the constraints (exit 1), an output that cannot be written (exit 4)
expect_plan 1 "too few poses meet the constraints" -- "${cell[@]}" "${out[@]}" --count 10 --floor-z 5
expect_plan 4 "does not exist" -- "${cell[@]}" --count 10 --out "$work/no/dir/p.csv"

# --- a good run with the defaults: CSV + URScript + report; then the same bytes for the same
# seed, other poses for another
good=("${cell[@]}" --count 30 --seed 7 --urscript "$work/s.script")
if "${run[@]}" plan "${good[@]}" --out "$work/a.csv" >"$work/report.txt" 2>&1; then
  if [ "$(head -1 "$work/a.csv")" = "q1,q2,q3,q4,q5,q6" ] && [ "$(wc -l <"$work/a.csv")" -eq 31 ]; then pass; else
    fail "plan CSV: header or row count"; fi
  if [ "$(grep -c '^  movej(\[' "$work/s.script")" -eq 30 ] && [ "$(grep -c '^  sleep(1)$' "$work/s.script")" -eq 30 ] &&
     grep -q '^def hivecal_session():$' "$work/s.script" && [ "$(tail -1 "$work/s.script")" = "end" ]; then pass; else
    fail "plan URScript: 30 movej + sleep(1) inside def ... end"; fi
  if grep -q "log det (D-criterion)" "$work/report.txt" && grep -q "predicted sigma at 10 um" "$work/report.txt" &&
     grep -q "^session: " "$work/report.txt"; then pass; else fail "plan report: $(cat "$work/report.txt")"; fi
  ur_result_json ur5e 0.1625 -0.425 -0.3922 0.1333 0.0997 0.0996 "0.0, 0.0, 0.05" \
    "[[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]" >"$work/result.json"
  # The CSV is the poses-to-predict format: every planned reflector above the 0.05 m floor.
  if "${run[@]}" predict --calibration "$work/result.json" --joints "$work/a.csv" --frame base --out "$work/p.csv" &&
     [ "$(awk -F, 'NR > 1 && $3 < 0.05' "$work/p.csv" | wc -l)" -eq 0 ] && [ "$(wc -l <"$work/p.csv")" -eq 31 ]; then pass; else
    fail "plan CSV through predict: a reflector below the floor or unreadable"; fi
else
  fail "plan on good input: $(cat "$work/report.txt")"
fi
"${run[@]}" plan "${cell[@]}" "${quick[@]}" --count 30 --seed 7 --out "$work/b.csv" >/dev/null 2>&1
"${run[@]}" plan "${cell[@]}" "${quick[@]}" --count 30 --seed 7 --out "$work/b2.csv" >/dev/null 2>&1
if [ -s "$work/b.csv" ] && cmp -s "$work/b.csv" "$work/b2.csv"; then pass; else fail "plan: not the same bytes for one seed"; fi
"${run[@]}" plan "${cell[@]}" "${quick[@]}" --count 30 --seed 8 --out "$work/c.csv" --svg "$work/f.svg" >/dev/null 2>&1
if [ "$(head -c 4 "$work/f.svg")" = "<svg" ] && grep -q ">planned<" "$work/f.svg" && grep -q ">random<" "$work/f.svg" &&
   [ "$(tail -1 "$work/f.svg")" = "</svg>" ]; then pass; else fail "plan --svg: figure"; fi
if [ -s "$work/c.csv" ] && ! cmp -s "$work/b.csv" "$work/c.csv"; then pass; else fail "plan: another seed gave the same poses"; fi

# --- the paper's situation: tool always down
if "${run[@]}" plan "${cell[@]}" "${quick[@]}" --count 30 --tool-down --out "$work/down.csv" >"$work/down.txt" 2>&1 &&
   grep -q "makes identifiable: a1 d4 tool_z" "$work/down.txt" && grep -q "  d6: null_combination" "$work/down.txt"; then pass; else
  fail "plan --tool-down report: $(cat "$work/down.txt")"; fi

# --- joint limits: a real arm's in degrees (J2 +-110 deg, J6 +-400 deg: more than one turn), from
# --joint-limits (units in the header, or --angle-unit) or from the description itself; every
# planned pose inside them. A description without limits: plan says what it assumes.
printf 'lower [deg],upper [deg]\n-360,360\n-110,110\n-150,150\n-360,360\n-360,360\n-400,400\n' >"$work/deg.csv"
inside_110() { awk -F, 'NR > 1 && ($2 < -1.9198621771937625 || $2 > 1.9198621771937625)' "$1" | wc -l; }
if "${run[@]}" plan "${cell[@]}" "${quick[@]}" --count 12 --joint-limits "$work/deg.csv" --out "$work/lim.csv" >/dev/null 2>&1 &&
   [ "$(inside_110 "$work/lim.csv")" -eq 0 ] && [ "$(wc -l <"$work/lim.csv")" -eq 13 ]; then pass; else
  fail "plan --joint-limits in [deg]: a pose outside J2 +-110 deg"; fi
tail -n +2 "$work/deg.csv" >"$work/deg_plain.csv"
sed -i '1i lower,upper' "$work/deg_plain.csv"
expect_plan 3 "a limit beyond two turns (4 pi rad): degrees?" -- "${cell[@]}" "${out[@]}" --count 10 --joint-limits "$work/deg_plain.csv"
if "${run[@]}" plan "${cell[@]}" "${quick[@]}" --count 12 --joint-limits "$work/deg_plain.csv" --angle-unit deg --out "$work/lim2.csv" >/dev/null 2>&1 &&
   cmp -s "$work/lim.csv" "$work/lim2.csv"; then pass; else fail "plan --joint-limits with --angle-unit deg"; fi
"${run[@]}" export --robot-model ur5e --format robot-json --out "$work/ur5e.json" 2>/dev/null
if "${run[@]}" plan "${cell[@]}" "${quick[@]}" --robot-model "$work/ur5e.json" --count 12 --out "$work/nolim.csv" 2>"$work/nolim.err" >/dev/null &&
   grep -q "gives no joint limits: assuming +-360 deg for every joint" "$work/nolim.err"; then pass; else
  fail "plan with a description without limits: $(cat "$work/nolim.err")"; fi
sed 's/^  "tool": /  "joint_limits": [[-6.28, 6.28], [-1.9198621771937625, 1.9198621771937625], [-2.6, 2.6], [-6.28, 6.28], [-6.28, 6.28], [-6.98, 6.98]],\n  "tool": /' \
  "$work/ur5e.json" >"$work/ur5e_lim.json"
if "${run[@]}" plan "${cell[@]}" "${quick[@]}" --robot-model "$work/ur5e_lim.json" --count 12 --out "$work/desc.csv" 2>"$work/desc.err" >/dev/null &&
   [ "$(inside_110 "$work/desc.csv")" -eq 0 ] && ! grep -q "gives no joint limits" "$work/desc.err"; then pass; else
  fail "plan with the description's joint_limits: $(cat "$work/desc.err")"; fi
sed 's/^  "tool": /  "joint_limits": [[1, -1], [-1, 1], [-1, 1], [-1, 1], [-1, 1], [-1, 1]],\n  "tool": /' "$work/ur5e.json" >"$work/ur5e_bad.json"
expect_plan 3 '"joint_limits"[0] = [1, -1] rad: lower must be below upper' -- "${cell[@]}" "${out[@]}" --count 10 --robot-model "$work/ur5e_bad.json"
# Limits beyond the arm's own range (+-12 rad on a UR5e, whose elbow turns +-180 deg and the
# others +-360 deg): clamped to it, each said; a joint whose range lies outside the arm's: refused.
printf 'lower,upper\n-12,12\n-12,12\n-12,12\n-12,12\n-12,12\n-12,12\n' >"$work/wide.csv"
if "${run[@]}" plan "${cell[@]}" "${quick[@]}" --count 30 --joint-limits "$work/wide.csv" --out "$work/wide_poses.csv" \
     2>"$work/wide.err" >/dev/null &&
   [ "$(grep -c "goes beyond the ur5e's own range" "$work/wide.err")" -eq 6 ] &&
   grep -q "joint 3 \[-12.0000, 12.0000\] rad goes beyond the ur5e's own range \[-3.1416, 3.1416\] rad: clamped to it" "$work/wide.err" &&
   awk -F, 'NR > 1 { for (j = 1; j <= 6; ++j) { v = $j < 0 ? -$j : $j; if (v > (j == 3 ? 3.14159266 : 6.28318531)) bad = 1 } }
     END { exit bad }' "$work/wide_poses.csv" && [ "$(wc -l <"$work/wide_poses.csv")" -eq 31 ]; then pass; else
  fail "plan --joint-limits beyond the arm's range: $(cat "$work/wide.err")"; fi
printf 'lower,upper\n7,8\n-1,1\n-1,1\n-1,1\n-1,1\n-1,1\n' >"$work/outside.csv"
expect_plan 3 "joint 1 [7.0000, 8.0000] rad lies outside the ur5e's own range [-6.2832, 6.2832] rad" -- "${cell[@]}" "${out[@]}" --count 10 --joint-limits "$work/outside.csv"
# --- nothing found: the message names the cause (an absurd tool, limits that leave no pose)
expect_plan 2 "--tool must be X,Y,Z in metres, each within [-10, 10] m, got '0,0,1e9'" -- "${cell[@]}" "${out[@]}" --count 10 --tool 0,0,1e9
expect_plan 1 "the tool is why: --tool 0,0,5 puts the reflector 5 m from the flange" -- "${cell[@]}" "${out[@]}" --count 10 --tool 0,0,5
printf 'lower,upper\n-0.01,0.01\n-0.01,0.01\n-0.01,0.01\n-0.01,0.01\n-0.01,0.01\n-0.01,0.01\n' >"$work/tight.csv"
expect_plan 1 "the joint limits are why: --joint-limits $work/tight.csv leave none" -- "${cell[@]}" "${out[@]}" --count 10 --joint-limits "$work/tight.csv"
expect_plan 1 "move the tracker" -- "${cell[@]}" "${out[@]}" --count 10 --floor-z 5

# --- the ISO 9283 test: the cube's five positions (P2..P5 on the diagonals, 10 % of a diagonal
# from the corners: 0.8 x half a diagonal from P1) with one orientation, and the cycles program
if "${run[@]}" plan --iso9283 0.4,-0.3,0.5,0.3 --tracker-position 2,0.5,0.6 --out "$work/iso.csv" --urscript "$work/iso.script" >/dev/null 2>&1 &&
   [ "$(wc -l <"$work/iso.csv")" -eq 6 ] &&
   awk -F, 'NR == 2 { x = $2; y = $3; z = $4; r = $5 "," $6 "," $7 } NR > 2 { d = sqrt(($2 - x)^2 + ($3 - y)^2 + ($4 - z)^2);
     if (d < 0.2078 || d > 0.2079 || $5 "," $6 "," $7 != r) bad = 1 } END { exit bad }' "$work/iso.csv" &&
   [ "$(grep -c '^    movel(p[1-5], a=1.2, v=0.25)$' "$work/iso.script")" -eq 5 ] && grep -q '^  while (cycle < 30):$' "$work/iso.script"; then pass; else
  fail "plan --iso9283: $(cat "$work/iso.csv" "$work/iso.script")"; fi
expect_plan 2 "--iso9283 must be X,Y,Z,SIDE" -- --iso9283 0.4,0.5,0.3 --tracker-position 2,0.5,0.6 "${out[@]}"
# An option of the other mode is refused, not dropped without a word.
expect_plan 2 "--count is an option of pose planning, not of the ISO 9283 test (--iso9283): leave it out" -- --iso9283 auto --count 10 --tracker-position 2,0.5,0.6 "${out[@]}"
expect_plan 2 "--cycles goes with --iso9283 (the ISO 9283 test)" -- "${cell[@]}" "${out[@]}" --count 10 --cycles 5
# A given cube is checked as auto's: too small, below the floor, inside the keep-out cylinder,
# out of reach or with an absurd tool: refused by position, nothing written (no URScript for
# positions the arm cannot take).
expect_plan 2 "--iso9283 X,Y,Z,SIDE: SIDE must be within [0.02, 10] m, got '1e-9'" -- --iso9283 0.4,-0.3,0.5,1e-9 --tracker-position 2,0.5,0.6 "${out[@]}"
expect_plan 1 "P2 (0.2800, -0.4200, -0.0700 m), P3 (0.5200, -0.4200, -0.0700 m): below --floor-z 0.05 m" -- --iso9283 0.4,-0.3,0.05,0.3 --tracker-position 2,0.5,0.6 "${out[@]}"
expect_plan 1 ": inside --keep-out-radius 0.15 m" -- --iso9283 0.1,0,0.5,0.1 --tracker-position 2,0.5,0.6 "${out[@]}"
expect_plan 1 "P1 (2.0000, 0.0000, 0.5000 m)" -- --iso9283 2,0,0.5,0.3 --tracker-position 3,0.5,0.6 "${out[@]}" --urscript "$work/iso_far.script"
no_file "$work/iso_far.script"
expect_plan 1 "the tool is why: --tool 0,0,5" -- --iso9283 0.4,-0.3,0.5,0.3 --tool 0,0,5 --tracker-position 2,0.5,0.6 "${out[@]}"
expect_plan 1 "--iso9283 auto: no cube whose five positions the arm reaches with one orientation (the tool is why" -- --iso9283 auto --tool 0,0,5 --tracker-position 2,0.5,0.6 "${out[@]}"
# auto: the largest cube found whose five positions the arm reaches with the one orientation;
# each listed joint solution puts the reflector there (checked through predict, the model's FK;
# the reflector at the flange, as predict's built-in ur5e has it)
if "${run[@]}" plan --iso9283 auto --robot-model ur5e --tool 0,0,0 --tracker-position 2,0.5,0.6 --out "$work/iso_auto.csv" >"$work/iso_auto.txt" 2>&1 &&
   cut -d, -f8-13 "$work/iso_auto.csv" >"$work/iso_q.csv" &&
   "${run[@]}" predict --robot-model ur5e --joints "$work/iso_q.csv" --out "$work/iso_fk.csv" 2>/dev/null &&
   paste -d, "$work/iso_fk.csv" <(cut -d, -f2-4 "$work/iso_auto.csv") | awk -F, 'NR > 1 {
     for (i = 1; i <= 3; ++i) { d = $i - $(i + 3); if (d < 0) d = -d; if (d > 1e-6) bad = 1 } } END { exit bad }' &&
   awk '{ for (i = 1; i <= NF; ++i) if ($i == "m" && $(i - 1) + 0 > 0.1 && $(i - 2) == "a") found = 1 } END { exit !found }' "$work/iso_auto.txt"; then pass; else
  fail "plan --iso9283 auto: $(cat "$work/iso_auto.txt" "$work/iso_auto.csv")"; fi

if "${run[@]}" plan --help | grep -q "usage: hivecal plan"; then pass; else fail "plan --help"; fi

finish
