#!/usr/bin/env bash
# Every public header of lib/ has its own test file: lib/include/hivecal/<stage>/<name>.hpp is
# tested in tests/lib/<stage>/test_<name>.cpp, a top-level one (hivecal/<name>.hpp, the job) in
# tests/lib/job/test_<name>.cpp. The umbrella header hivecal/hivecal.hpp only includes the
# others. Lists every header without its test file and exits 1 if there is any.
set -uo pipefail
cd "$(dirname "$0")/.."

missing=0
count=0
while IFS= read -r header; do
  rel=${header#lib/include/hivecal/}
  name=$(basename "$rel" .hpp)
  case "$rel" in
    hivecal.hpp) continue ;;
    */*) test_file="tests/lib/${rel%%/*}/test_${name}.cpp" ;;
    *) test_file="tests/lib/job/test_${name}.cpp" ;;
  esac
  count=$((count + 1))
  if [ ! -f "$test_file" ]; then
    echo "$header: no $test_file"
    missing=$((missing + 1))
  fi
done < <(find lib/include/hivecal -name '*.hpp' | sort)

if [ "$missing" -ne 0 ]; then
  echo "check-header-tests: $missing of $count public header(s) without a test file"
  exit 1
fi
echo "check-header-tests: each of the $count public headers has its test file"
