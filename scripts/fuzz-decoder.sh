#!/usr/bin/env bash
# Builds the StreamDecoder libFuzzer target (clang, ASan + UBSan; `fuzz` preset) and runs it
# for a bounded time on a seed corpus made from the spec's test vectors.
#   scripts/fuzz-decoder.sh [seconds]      (default 60)
# Exits non-zero if the build fails or the fuzzer finds a crash, a sanitizer report or a
# broken invariant (tests/fuzz/decoder_fuzz.cpp traps on those).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"

cmake --preset fuzz >/dev/null
cmake --build --preset fuzz -j2 --target decoder_fuzz

work=build/fuzz/run
corpus="$work/corpus"
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

log="$work/fuzz.log"
set +e
build/fuzz/tests/fuzz/decoder_fuzz -max_total_time="$seconds" -max_len=4096 -print_final_stats=1 \
  -artifact_prefix="$work/" "$corpus" >"$log" 2>&1
rc=$?
set -e
grep -E "^(INFO: seed corpus|#[0-9]+[[:space:]]+DONE)|stat::number_of_executed_units|stat::peak_rss|ERROR|SUMMARY|runtime error" "$log" || true
if [ "$rc" -ne 0 ]; then
  echo "fuzz-decoder: FAILED (exit $rc); log: $log, crash input: $work/crash-*" >&2
  exit "$rc"
fi
echo "fuzz-decoder: no crash, no sanitizer report in ${seconds}s (log: $log)"
