#!/usr/bin/env bash
# Enforces the include rules of lib/ (docs/architecture.md): each stage folder may include only
# the stages below it, and nothing in lib/ includes the OS, the heap containers or I/O streams.
#   core   <- (nothing)           wire <- core          model <- core, linalg
#   linalg <- core                sync <- core, wire, model
#   solve  <- core, linalg, model          plan <- core, linalg, model, solve
#   job (hivecal/*.hpp, src/job) <- every stage
# Prints each violation as file:line and exits 1 if there is any.
set -uo pipefail
cd "$(dirname "$0")/.."

allowed() {  # allowed STAGE -> the stages it may include
  case "$1" in
    core) echo "core" ;;
    wire) echo "core wire" ;;
    linalg) echo "core linalg" ;;
    model) echo "core linalg model" ;;
    sync) echo "core wire model sync" ;;
    solve) echo "core linalg model solve" ;;
    plan) echo "core linalg model solve plan" ;;
    job) echo "core wire sync model linalg solve plan job" ;;
    *) echo "" ;;
  esac
}

stage_of() {  # stage_of PATH -> the stage folder of a lib/ file
  local rel=${1#lib/include/hivecal/}
  rel=${rel#lib/src/}
  case "$rel" in
    */*) echo "${rel%%/*}" ;;
    *) echo job ;;  # top-level headers (hivecal.hpp, calibration.hpp)
  esac
}

forbidden_system='iostream|fstream|sstream|vector|string|map|unordered_map|set|list|deque|memory|functional|thread|mutex|chrono|regex|exception|stdexcept|typeinfo|cstdio|stdio\.h|unistd\.h|fcntl\.h|sys/.*'
violations=0
while IFS= read -r file; do
  stage=$(stage_of "$file")
  ok=$(allowed "$stage")
  while IFS=: read -r line text; do
    if [[ $text =~ \#include[[:space:]]*\"hivecal/([a-z0-9_]+)/ ]]; then
      target=${BASH_REMATCH[1]}
    elif [[ $text =~ \#include[[:space:]]*\"hivecal/[a-z0-9_]+\.hpp\" ]]; then
      target=job
    elif [[ $text =~ \#include[[:space:]]*\"([a-z0-9_]+)/[a-z0-9_]+\.hpp\" ]]; then
      target=${BASH_REMATCH[1]}  # library-internal header under lib/src
    elif [[ $text =~ \#include[[:space:]]*\<($forbidden_system)\> ]]; then
      echo "$file:$line: lib/ must not include <${BASH_REMATCH[1]}> (no OS, heap containers or streams)"
      violations=$((violations + 1))
      continue
    elif [[ $text =~ \#include[[:space:]]*\" ]]; then
      echo "$file:$line: include by stage path (\"hivecal/<stage>/x.hpp\" or \"<stage>/x.hpp\"): $text"
      violations=$((violations + 1))
      continue
    else
      continue
    fi
    if [[ " $ok " != *" $target "* ]]; then
      echo "$file:$line: stage '$stage' may not include stage '$target' (allowed: $ok)"
      violations=$((violations + 1))
    fi
  done < <(grep -n '^[[:space:]]*#[[:space:]]*include' "$file")
done < <(find lib/include lib/src -type f \( -name '*.hpp' -o -name '*.cpp' -o -name '*.h' \) | sort)

if [ "$violations" -ne 0 ]; then
  echo "check-includes: $violations violation(s)"
  exit 1
fi
echo "check-includes: lib/ include rules hold ($(find lib/include lib/src -type f | wc -l) files)"
