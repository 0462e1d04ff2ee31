#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, ASan + UBSan; `fuzz` preset) and runs both at once, each
# for a bounded time on a seed corpus: the StreamDecoder (seeds: the spec's test vectors) and the
# log readers of apps/textio (seeds: the logs of io-formats.md and a CDR JointState).
#   scripts/fuzz-decoder.sh [decoder-seconds] [log-seconds]      (default 60 and 30)
# Exits non-zero if a build fails or a fuzzer finds a crash, a sanitizer report or a
# broken invariant (tests/fuzz/decoder_fuzz.cpp and log_fuzz.cpp trap on those).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
log_seconds="${2:-30}"

cmake --preset fuzz >/dev/null
cmake --build --preset fuzz -j2 --target decoder_fuzz log_fuzz

work=build/fuzz/run
corpus="$work/decoder_fuzz/corpus"
rm -rf "$work"
mkdir -p "$corpus"
# Input layout: byte 0 = largest chunk - 1, byte 1 = chunk-size seed, then the wire bytes.
v1=040101070440420f01010101010101010101010121182d4454fb21f9bf182d4454fb21f93f182d4454fb21f9bf182d4454fb21f9bf010101010101010101010101010101010101010101010101010101010101010101010101010101010101010101010101010101010101010101010101010101010101010101010101010101010101010502256b2800
v2=090102ffff15cd5b0701010101010101010103f43f010101010103e0bf010101010103e83f010101058b23b33d00
v3=0301030101010101010101010202010101010e2041747261636b65722d73696d01010101010101010101010105540a210a00
seed() { printf "$(sed 's/../\\x&/g' <<<"$2")" >"$corpus/$1"; }
seed joint_state "ff00$v1"
seed tracker_point "0001$v2"
seed device_info "0702$v3"
seed all_three "1003$v3$v1$v2$v2"
seed mid_frame "0004${v1:40}$v2"
seed idle_and_noise "2005000000${v2}41424300$v3"

# run NAME SECONDS MAX_LEN: runs build/fuzz/tests/fuzz/NAME on $work/NAME/corpus and prints
# its summary; returns libFuzzer's exit code (non-zero on a finding).
run() {
  local log="$work/$1.log" rc=0
  "build/fuzz/tests/fuzz/$1" -max_total_time="$2" -max_len="$3" -print_final_stats=1 \
    -artifact_prefix="$work/$1-" "$work/$1/corpus" >"$log" 2>&1 || rc=$?
  grep -E "^(INFO: seed corpus|#[0-9]+[[:space:]]+DONE)|stat::number_of_executed_units|stat::peak_rss|ERROR|SUMMARY|runtime error" "$log" || true
  if [ "$rc" -ne 0 ]; then
    echo "fuzz-decoder: $1 FAILED (exit $rc); log: $log, crash input: $work/$1-crash-*" >&2
    return "$rc"
  fi
  echo "fuzz-decoder: $1: no crash, no sanitizer report in ${2}s (log: $log)"
}

# Log seeds: byte 0 = reader (0 robot log, 1 tracker log, 2 CDR JointState), then the file.
corpus="$work/log_fuzz/corpus"
mkdir -p "$corpus"
text() { printf '%s' "$2" >"$corpus/$1"; }
text hivecal_robot $'0t,q1,q2,q3,q4,q5,q6\n12.008,0.0,-1.5707963267948966,1.5707963267948966,-1.5707963267948966,-1.5707963267948966,0.0\n12.016,0,0,0,0,0,1e-3\n'
text rtde $'0timestamp target_q_0 target_q_1 target_q_2 target_q_3 target_q_4 target_q_5 actual_q_0 actual_q_1 actual_q_2 actual_q_3 actual_q_4 actual_q_5\n1.002 0 0 0 0 0 0 0.1 0.2 0.3 0.4 0.5 0.6\n1.004 0 0 0 0 0 0 0.1 0.2 0.3 0.4 0.5 0.6\n'
text rostopic $'0%time,field.header.seq,field.header.stamp,field.header.frame_id,field.name0,field.name1,field.name2,field.name3,field.name4,field.name5,field.position0,field.position1,field.position2,field.position3,field.position4,field.position5\n1000500000,0,1000000000,,elbow_joint,shoulder_lift_joint,shoulder_pan_joint,wrist_1_joint,wrist_2_joint,wrist_3_joint,3,2,1,4,5,6\n'
text hivecal_tracker $'1t,x,y,z,status\n3.100,1.2500,-0.5000,0.7500,0\n3.2,nan,nan,nan,1\n'
text export $'1\xef\xbb\xbfTime [ms];X [mm];Y [mm];Z [mm]\r\n1500;1000.5;2;3\r\n1600;1000,5;2;3\r\n'
text spaces $'1Time [s] X [um] Y [um] Z [um]\n1.5 1000000 2 3\n'
seed cdr_joint_state "0200010000702c426715cd5b070a000000626173655f6c696e6b000000020000000200000061000000030000006262000002000000000000000000f03f00000000000000400000000000000000"

# Both fuzzers at once (one core each: libFuzzer runs one process), each summary printed whole.
run decoder_fuzz "$seconds" 4096 >"$work/decoder_fuzz.summary" 2>&1 &
decoder_pid=$!
log_rc=0
run log_fuzz "$log_seconds" 8192 >"$work/log_fuzz.summary" 2>&1 || log_rc=$?
decoder_rc=0
wait "$decoder_pid" || decoder_rc=$?
cat "$work/decoder_fuzz.summary" "$work/log_fuzz.summary"
[ "$decoder_rc" -eq 0 ] && [ "$log_rc" -eq 0 ]
