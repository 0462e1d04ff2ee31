#!/usr/bin/env bash
# The GoogleTest files are compiled eight to a translation unit (CMakeLists.txt,
# HIVECAL_UNITY_BUILD), so each keeps its names in a namespace of its own: every namespace a
# file tests/<suite>/test_<name>.cpp opens at the top level ends in <name>_test
# (hivecal::<name>_test, hivecal::port::<name>_test, ...), and an anonymous one only inside it.
# Two files of one batch then cannot define the same helper. Lists every file that breaks the
# rule and exits 1 if there is any.
set -uo pipefail
cd "$(dirname "$0")/.."

bad=0
count=0
while IFS= read -r file; do
  name=$(basename "$file" .cpp)
  name=${name#test_}
  count=$((count + 1))
  # Top-level namespace lines (column 0); an anonymous one must come right after its file's own.
  wrong=$(awk -v own="${name}_test" '
    /^namespace [A-Za-z0-9_:]+ \{/ {
      id = $2
      sub(/.*::/, "", id)
      if (id != own) print FNR ": " $0
      last = FNR
      opened = 1
      next
    }
    /^namespace \{/ { if (last != FNR - 1) print FNR ": " $0 }
    END { if (!opened) print "no namespace at all" }' "$file")
  if [ -n "$wrong" ]; then
    echo "$file: a top-level namespace that is not ...::${name}_test:"
    sed 's/^/  /' <<<"$wrong"
    bad=$((bad + 1))
  fi
done < <(find tests -name 'test_*.cpp' -not -path 'tests/firmware/*' | sort)

if [ "$bad" -ne 0 ]; then
  echo "check-test-namespaces: $bad of $count test file(s) without a namespace of their own"
  exit 1
fi
echo "check-test-namespaces: each of the $count test files keeps its names in <name>_test"
