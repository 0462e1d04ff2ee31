# Bare-metal Cortex-M4F: its FPU (fpv4-sp-d16) is single precision only, so every double
# operation is a libgcc soft-float call (IEEE-754 correctly rounded: same bits, just slower).
# Firmware tests run under qemu-system-arm -M mps2-an386 (Cortex-M4) with semihosting.
set(HIVECAL_MCU_FLAGS "-mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard")
set(HIVECAL_QEMU_MACHINE mps2-an386)
include(${CMAKE_CURRENT_LIST_DIR}/arm-none-eabi-common.cmake)
