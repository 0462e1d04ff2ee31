#!/usr/bin/env bash
# Fails when an image exceeds its budgets (arm-none-eabi-size): flash = text + data, static RAM
# = data + bss (the stack section, .stack, is counted in bss by arm-none-eabi-size).
#   scripts/check-image-budget.sh <image.elf> <flash-budget-bytes> [<ram-budget-bytes>]
set -euo pipefail
elf=$1
flash_budget=$2
ram_budget=${3:-}
read -r text data bss < <(arm-none-eabi-size "$elf" | awk 'NR == 2 { print $1, $2, $3 }')
flash=$((text + data))
ram=$((data + bss))
status=0
echo "flash of $(basename "$elf"): $flash bytes of $flash_budget ($((flash_budget - flash)) left)"
if [ "$flash" -gt "$flash_budget" ]; then
  echo "over the flash budget by $((flash - flash_budget)) bytes" >&2
  status=1
fi
if [ -n "$ram_budget" ]; then
  echo "static RAM of $(basename "$elf") (stack included): $ram bytes of $ram_budget ($((ram_budget - ram)) left)"
  if [ "$ram" -gt "$ram_budget" ]; then
    echo "over the RAM budget by $((ram - ram_budget)) bytes" >&2
    status=1
  fi
fi
exit "$status"
