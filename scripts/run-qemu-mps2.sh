#!/usr/bin/env bash
# Runs a bare-metal firmware ELF on a QEMU MPS2 board with semihosting; the exit code is the
# firmware's (0 ok, 1 failed checks, 2 fault/assert/abort; see port/baremetal board.h),
# 124 on timeout. CTest calls it as the CMAKE_CROSSCOMPILING_EMULATOR of the arm-none-eabi
# toolchains.
#   scripts/run-qemu-mps2.sh <machine> <firmware.elf> [firmware args...]
# Environment:
#   HIVECAL_QEMU_TIMEOUT   seconds before the run is killed (default 600)
#   HIVECAL_QEMU_EXTRA     extra qemu-system-arm options, e.g.
#                          "-plugin build/cortex-m7/libinsncount.so -d plugin"
set -uo pipefail

if [ $# -lt 2 ]; then
  echo "usage: $0 <machine> <firmware.elf> [args...]" >&2
  exit 64
fi
machine=$1
elf=$2
shift 2

# The firmware reads its arguments with SYS_GET_CMDLINE: program name first, like argv.
semihosting="enable=on,target=native,arg=$(basename "$elf")"
for arg in "$@"; do
  semihosting+=",arg=$arg"
done

# shellcheck disable=SC2086  # HIVECAL_QEMU_EXTRA is a word list on purpose
timeout --foreground "${HIVECAL_QEMU_TIMEOUT:-600}" \
  qemu-system-arm -M "$machine" -nographic -monitor none -serial none \
  -semihosting-config "$semihosting" ${HIVECAL_QEMU_EXTRA:-} -kernel "$elf" </dev/null
status=$?
case $status in
  0) ;;
  1) echo "run-qemu-mps2: firmware main returned non-zero (failed checks)" >&2 ;;
  2) echo "run-qemu-mps2: firmware stopped on a fault, assert or abort" >&2 ;;
  124) echo "run-qemu-mps2: timed out after ${HIVECAL_QEMU_TIMEOUT:-600} s" >&2 ;;
  *) echo "run-qemu-mps2: qemu-system-arm exited with status $status" >&2 ;;
esac
exit $status
