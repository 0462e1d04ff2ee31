#!/usr/bin/env bash
# Runs every test on every target: host at -O3 and with ASan+UBSan, aarch64 under qemu-user,
# the golden digests at -O0, -march=native (with 28 joint terms) and on armhf (HIVECAL_TEST_SCOPE=golden: what those
# flags and that target can change is the bits), then the bare-metal Cortex-M7 (hardware doubles) and
# Cortex-M4F (soft-float doubles) firmware under qemu-system-arm, then the wire decoder
# fuzzer for HIVECAL_FUZZ_SECONDS (default 60) beside the log-reader fuzzer for 30 s. Installs what it needs first.
#   scripts/test-all.sh [preset ...]     (default: all of them)
set -uo pipefail
cd "$(dirname "$0")/.."

scripts/install-deps.sh || { echo "test-all: dependency install failed" >&2; exit 1; }

presets=("$@")
if [ ${#presets[@]} -eq 0 ]; then
  presets=(host host-O0 host-native host-asan aarch64 armhf cortex-m7 cortex-m4 fuzz)
fi

passed=0
failed=0
failed_presets=()
for preset in "${presets[@]}"; do
  echo "=== $preset ==="
  started_s=$SECONDS
  log="build/test-$preset.log"
  mkdir -p build
  if [ "$preset" = fuzz ]; then
    # The decoder and log-reader fuzz targets for a bounded time (ASan + UBSan); one test, pass or fail.
    scripts/fuzz-decoder.sh "${HIVECAL_FUZZ_SECONDS:-60}" >"$log" 2>&1
    rc=$?
    tail -3 "$log"
    if [ "$rc" -eq 0 ]; then echo "100% tests passed, 0 tests failed out of 1" >>"$log"; fi
  else
    cmake --workflow --preset "$preset" >"$log" 2>&1
    rc=$?
  fi
  grep -E "[0-9]+% tests passed|The following tests FAILED|^\s+[0-9]+ - |error:|Failed" "$log" | head -40
  echo "($preset: $((SECONDS - started_s)) s, build and tests)"
  result=$(grep -E "tests passed, [0-9]+ tests failed out of [0-9]+" "$log" | tail -1)
  if [ "$rc" -ne 0 ] || [ -z "$result" ] || ! grep -q " 0 tests failed" <<<"$result"; then
    failed_presets+=("$preset")
  fi
  total=$(sed -E 's/.*out of ([0-9]+).*/\1/' <<<"$result")
  bad=$(sed -E 's/.*passed, ([0-9]+) tests failed.*/\1/' <<<"$result")
  if [ -n "$result" ]; then
    passed=$((passed + total - bad))
    failed=$((failed + bad))
  fi
done

echo
echo "test-all: ${SECONDS} s in all"
if [ ${#failed_presets[@]} -ne 0 ]; then
  echo "test-all: FAILED presets: ${failed_presets[*]} (logs in build/test-<preset>.log)"
  [ "$failed" -eq 0 ] && failed=1
fi
echo "$passed passed, $failed failed"
[ ${#failed_presets[@]} -eq 0 ]
