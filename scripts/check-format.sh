#!/usr/bin/env bash
# Every C and C++ file of the repository is formatted as .clang-format says (Debian 12's
# clang-format 14, installed by scripts/install-deps.sh). Lists the files that are not and exits
# 1 if there is any; `scripts/check-format.sh --fix` formats them in place.
set -uo pipefail
cd "$(dirname "$0")/.."

if ! command -v clang-format >/dev/null; then
  echo "check-format: clang-format not found (scripts/install-deps.sh installs it)" >&2
  exit 1
fi
mapfile -t files < <(git ls-files '*.c' '*.h' '*.cpp' '*.hpp' 2>/dev/null || find lib port apps tests examples -name '*.[ch]pp' -o -name '*.[ch]')
if [ "${1:-}" = --fix ]; then
  clang-format -i "${files[@]}"
  exit 0
fi
# One clang-format over every file; its findings name file:line:col of each misformatted place.
findings=$(clang-format --dry-run --Werror "${files[@]}" 2>&1 | grep -oE '^[^:]+:[0-9]+:[0-9]+: (error|warning)' | cut -d: -f1 | sort -u)
if [ -n "$findings" ]; then
  sed 's/$/: not formatted (scripts\/check-format.sh --fix)/' <<<"$findings"
  echo "check-format: $(wc -l <<<"$findings") of ${#files[@]} files not formatted as .clang-format says"
  exit 1
fi
echo "check-format: all ${#files[@]} C/C++ files formatted"
