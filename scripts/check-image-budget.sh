#!/usr/bin/env bash
# Fails when an image's flash (text + data, arm-none-eabi-size) exceeds a budget in bytes.
#   scripts/check-flash-budget.sh <image.elf> <budget-bytes>
set -euo pipefail
elf=$1
budget=$2
read -r text data _ < <(arm-none-eabi-size "$elf" | awk 'NR == 2 { print $1, $2, $3 }')
flash=$((text + data))
echo "flash of $(basename "$elf"): $flash bytes of $budget ($((budget - flash)) left)"
[ "$flash" -le "$budget" ] || { echo "over the flash budget by $((flash - budget)) bytes" >&2; exit 1; }
