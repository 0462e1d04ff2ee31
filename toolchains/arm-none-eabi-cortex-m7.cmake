# Bare-metal Cortex-M7 with the double-precision FPU (fpv5-d16): doubles in hardware.
# Firmware tests run under qemu-system-arm -M mps2-an500 (Cortex-M7) with semihosting.
set(HIVECAL_MCU_FLAGS "-mcpu=cortex-m7 -mthumb -mfpu=fpv5-d16 -mfloat-abi=hard")
set(HIVECAL_QEMU_MACHINE mps2-an500)
include(${CMAKE_CURRENT_LIST_DIR}/arm-none-eabi-common.cmake)
