# Helpers of the command-line tests (cli_test.sh, plan_cli_test.sh), sourced with the test's
# own arguments:
#   source cli_lib.sh <hivecal binary> [emulator words...]
# Sets run (the command words), work (a temporary folder, removed at exit), passed, failed.
bin=$1
shift
run=("$@" "$bin")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
passed=0
failed=0

# pass: counts a check that held. fail WHAT...: counts one that did not, and says what.
pass() { passed=$((passed + 1)); }
fail() { failed=$((failed + 1)); echo "FAIL: $*"; }

# expect CODE SUBSTRING... -- ARGS...: runs hivecal ARGS once, checks the exit code and that
# stderr holds every SUBSTRING.
expect() {
  local code=$1
  shift
  local patterns=()
  while [ "$1" != "--" ]; do
    patterns+=("$1")
    shift
  done
  shift
  local err got pattern missing=""
  err=$("${run[@]}" "$@" 2>&1 >/dev/null)
  got=$?
  for pattern in "${patterns[@]}"; do
    grep -qF -- "$pattern" <<<"$err" || missing+=" '$pattern'"
  done
  if [ "$got" -eq "$code" ] && [ -z "$missing" ]; then pass; else
    fail "hivecal $* -> exit $got (want $code), stderr: $err (missing:$missing)"; fi
}

# no_file PATH: the output must not exist (nor a temporary of it) after a failed run.
no_file() {
  if [ -e "$1" ] || compgen -G "$1.tmp.*" >/dev/null; then fail "partial output left at $1"; else pass; fi
}

# ur_result_json ROBOT D1 A2 A3 D4 D5 D6 TOOL BASE: a robot-calibration/1 result of a UR-shaped
# arm (standard DH, a UR's twists, no theta offsets) [m]; TOOL is "x, y, z" [m], BASE the rows
# of base_to_tracker as a JSON array.
ur_result_json() {
  local h=1.5707963267948966
  cat <<JSON
{
  "format": "robot-calibration/1",
  "robot": "$1",
  "convention": "standard-dh",
  "dh": [
    {"theta_offset": 0.0, "d": $2, "a": 0.0, "alpha": $h},
    {"theta_offset": 0.0, "d": 0.0, "a": $3, "alpha": 0.0},
    {"theta_offset": 0.0, "d": 0.0, "a": $4, "alpha": 0.0},
    {"theta_offset": 0.0, "d": $5, "a": 0.0, "alpha": $h},
    {"theta_offset": 0.0, "d": $6, "a": 0.0, "alpha": -$h},
    {"theta_offset": 0.0, "d": $7, "a": 0.0, "alpha": 0.0}
  ],
  "tool": [$8],
  "base_to_tracker": $9
}
JSON
}

# finish: prints the counts; its status is the test's verdict.
finish() {
  echo "$passed passed, $failed failed"
  [ "$failed" -eq 0 ]
}
