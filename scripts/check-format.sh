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
unformatted=0
for f in "${files[@]}"; do
  if ! clang-format --dry-run --Werror "$f" >/dev/null 2>&1; then
    echo "$f: not formatted (scripts/check-format.sh --fix)"
    unformatted=$((unformatted + 1))
  fi
done
if [ "$unformatted" -ne 0 ]; then
  echo "check-format: $unformatted of ${#files[@]} files not formatted as .clang-format says"
  exit 1
fi
echo "check-format: all ${#files[@]} C/C++ files formatted"
