#!/usr/bin/env bash
# A file of lib/ says one concern: a source (.cpp) holds at most 900 lines and a header (.hpp,
# public or internal) at most 600; a longer one is split by concern (the calibration job:
# lib/src/job/*.cpp, lib/include/hivecal/job/*.hpp). Lists every file over its limit with its
# length and exits 1 if there is any.
set -uo pipefail
cd "$(dirname "$0")/.."

readonly kMaxSourceLines=900
readonly kMaxHeaderLines=600
over=0
count=0
while IFS= read -r file; do
  case "$file" in
    *.cpp) limit=$kMaxSourceLines ;;
    *) limit=$kMaxHeaderLines ;;
  esac
  lines=$(wc -l <"$file")
  count=$((count + 1))
  if [ "$lines" -gt "$limit" ]; then
    echo "$file: $lines lines, over $limit: split it by concern"
    over=$((over + 1))
  fi
done < <(find lib/include lib/src -type f \( -name '*.cpp' -o -name '*.hpp' -o -name '*.h' \) | sort)

if [ "$over" -ne 0 ]; then
  echo "check-file-lengths: $over of $count lib/ file(s) over their limit (.cpp $kMaxSourceLines, headers $kMaxHeaderLines lines)"
  exit 1
fi
echo "check-file-lengths: each of the $count lib/ files within its limit (.cpp $kMaxSourceLines, headers $kMaxHeaderLines lines)"
