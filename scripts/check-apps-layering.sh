#!/usr/bin/env bash
# Enforces the layering of apps/ and port/ (docs/architecture.md, "Layers"), as check-includes.sh
# does for lib/: each folder may include only the folders below it.
#   port/     <- its own headers and lib's byte-reader interface only (no math)
#   textio    <- lib, port                 report, streams <- lib, port, textio
#   record    <- lib, port, textio, report, streams (the result file)
#   sim       <- lib, port, textio, record (its truth file has the result's shape)
#   cli       <- lib, port, textio         commands <- every apps folder but bench and hivecal
#   hivecal   <- port, commands            bench    <- lib, textio, testkit (and its own peer)
# "lib" is "hivecal/<stage>/..." or "hivecal/<name>.hpp"; "port" is "hivecal/port/...".
# Prints each violation as file:line and exits 1 if there is any.
set -uo pipefail
cd "$(dirname "$0")/.."

allowed() {  # allowed FOLDER -> the include roots it may use
  case "$1" in
    textio) echo "lib port textio" ;;
    report | streams) echo "lib port textio $1" ;;
    record) echo "lib port textio report streams record" ;;
    sim) echo "lib port textio record sim" ;;
    cli) echo "lib port textio cli" ;;
    commands) echo "lib port textio report streams record sim cli commands" ;;
    hivecal) echo "port commands" ;;
    bench) echo "lib textio testkit bench" ;;
    *) echo "" ;;
  esac
}

root_of() {  # root_of INCLUDE-PATH -> lib, port or the apps folder
  case "$1" in
    hivecal/port/*) echo port ;;
    hivecal/*) echo lib ;;
    */*) echo "${1%%/*}" ;;
    *) echo local ;;  # a header beside the file ("ceres_peer.hpp")
  esac
}

violations=0
report() {
  echo "$1"
  violations=$((violations + 1))
}

while IFS= read -r file; do
  folder=${file#apps/}
  folder=${folder%%/*}
  ok="$(allowed "$folder") local"
  while IFS=: read -r line path; do
    root=$(root_of "$path")
    [[ " $ok " == *" $root "* ]] || report "$file:$line: apps/$folder may not include \"$path\" (allowed: $ok)"
  done < <(grep -noE '^[[:space:]]*#[[:space:]]*include[[:space:]]*"[^"]+"' "$file" | sed -E 's/:[^"]*"/:/; s/"$//')
done < <(find apps -type f \( -name '*.hpp' -o -name '*.cpp' \) | sort)

# port/ knows nothing of the math: its own headers, the board's, and lib's byte-reader interface.
while IFS=: read -r file line path; do
  case "$path" in
    hivecal/port/* | hivecal/wire/byte_reader.hpp | baremetal/* | semihosting* | stack*) ;;
    hivecal/*) report "$file:$line: port/ may not include \"$path\" (only hivecal/port/ and hivecal/wire/byte_reader.hpp of lib)" ;;
  esac
done < <(grep -rnoE '^[[:space:]]*#[[:space:]]*include[[:space:]]*"[^"]+"' port | sed -E 's/:[^":]*"/:/; s/"$//')

if [ "$violations" -ne 0 ]; then
  echo "check-apps-layering: $violations violation(s)"
  exit 1
fi
echo "check-apps-layering: apps/ and port/ layering holds ($(find apps port -type f \( -name '*.hpp' -o -name '*.cpp' \) | wc -l) files)"
