# Shared part of the bare-metal Cortex-M toolchains (included by arm-none-eabi-cortex-m*.cmake,
# which set HIVECAL_MCU_FLAGS and HIVECAL_QEMU_MACHINE first). Tests run the firmware ELF under
# qemu-system-arm with semihosting (scripts/run-qemu-mps2.sh passes the ELF as -kernel).
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)
set(CMAKE_C_COMPILER arm-none-eabi-gcc)
set(CMAKE_CXX_COMPILER arm-none-eabi-g++)
# Without an OS the compiler checks cannot link an executable; a static library suffices.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

# Sections per function/object so --gc-sections drops what the firmware does not call.
# C++ without exceptions/RTTI (no unwinder, no __cxa_allocate_exception -> malloc) and without
# thread-safe statics (libstdc++'s guard can throw recursive_init_error, which allocates).
# -fstack-usage / -fcallgraph-info=su write a .su and a .ci (call graph with frame sizes) per
# object for the stack report of scripts/footprint.sh. newlib-nano headers to match the libs.
set(_hivecal_common_flags
  "${HIVECAL_MCU_FLAGS} --specs=nano.specs -ffunction-sections -fdata-sections -fstack-usage -fcallgraph-info=su")
set(CMAKE_C_FLAGS_INIT "${_hivecal_common_flags}")
set(CMAKE_CXX_FLAGS_INIT "${_hivecal_common_flags} -fno-exceptions -fno-rtti -fno-threadsafe-statics")
# The compile flags above (CPU, newlib-nano specs) are on the link line too. No crt0
# (port/baremetal brings the vector table and reset handler) and no libnosys (it defines
# _sbrk: without it any heap use fails to link).
set(CMAKE_EXE_LINKER_FLAGS_INIT "-nostartfiles -Wl,--gc-sections")

set(CMAKE_FIND_ROOT_PATH /usr/lib/arm-none-eabi)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE BOTH)
# Eigen is header-only and architecture independent: the host's package config is fine.
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE BOTH)
list(APPEND CMAKE_PREFIX_PATH /usr)

set(CMAKE_CROSSCOMPILING_EMULATOR ${CMAKE_CURRENT_LIST_DIR}/../scripts/run-qemu-mps2.sh ${HIVECAL_QEMU_MACHINE})
