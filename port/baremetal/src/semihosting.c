/* Semihosting console, command line and exit for QEMU (-semihosting-config enable=on). */
#include "semihosting.h"

#include "baremetal/board.h"

intptr_t semihosting_call(uint32_t op, const void* arg) {
  intptr_t result;
  /* M-profile traps semihosting on BKPT 0xAB; r0 = operation, r1 = parameter, r0 = result. */
  __asm__ volatile(
      "mov r0, %1\n\t"
      "mov r1, %2\n\t"
      "bkpt 0xab\n\t"
      "mov %0, r0"
      : "=r"(result)
      : "r"(op), "r"(arg)
      : "r0", "r1", "memory");
  return result;
}

void board_write(const char* text) {
  (void)semihosting_call(SEMIHOSTING_SYS_WRITE0, text);
}

void board_write_char(char c) {
  (void)semihosting_call(SEMIHOSTING_SYS_WRITEC, &c);
}

_Noreturn void board_exit(int status) {
  /* SYS_EXIT_EXTENDED carries the status; plain SYS_EXIT on AArch32 could only say 0 or 1. */
  /* Static, not on the stack: a fault handler may call this with the stack in a bad state. */
  static uint32_t block[2];
  block[0] = SEMIHOSTING_ADP_STOPPED_APPLICATION_EXIT;
  block[1] = (uint32_t)status;
  (void)semihosting_call(SEMIHOSTING_SYS_EXIT_EXTENDED, block);
  /* A debugger without the extension returns here: fall back to the 0-or-1 form. */
  (void)semihosting_call(SEMIHOSTING_SYS_EXIT, (const void*)(uintptr_t)SEMIHOSTING_ADP_STOPPED_APPLICATION_EXIT);
  for (;;) {
  }
}

const char* board_command_line(void) {
  static char line[256];
  static int fetched;
  if (!fetched) {
    fetched = 1;
    uint32_t block[2] = {(uint32_t)(uintptr_t)line, (uint32_t)sizeof line};
    if (semihosting_call(SEMIHOSTING_SYS_GET_CMDLINE, block) != 0) line[0] = '\0';
  }
  /* QEMU puts the program name first (the first arg=); callers want what follows it. */
  const char* rest = line;
  while (*rest != '\0' && *rest != ' ') ++rest;
  while (*rest == ' ') ++rest;
  return rest;
}

int board_file_open(const char* path) {
  size_t length = 0;
  while (path[length] != '\0') ++length;
  /* Mode 1 is fopen's "rb". */
  const uint32_t block[3] = {(uint32_t)(uintptr_t)path, 1u, (uint32_t)length};
  return (int)semihosting_call(SEMIHOSTING_SYS_OPEN, block);
}

long board_file_read(int handle, void* out, size_t capacity) {
  const uint32_t block[3] = {(uint32_t)handle, (uint32_t)(uintptr_t)out, (uint32_t)capacity};
  /* SYS_READ returns the number of bytes NOT read: capacity at the end of the file. */
  const intptr_t not_read = semihosting_call(SEMIHOSTING_SYS_READ, block);
  if (not_read < 0 || (size_t)not_read > capacity) return -1;
  return (long)(capacity - (size_t)not_read);
}

int board_file_rewind(int handle) {
  const uint32_t block[2] = {(uint32_t)handle, 0u};
  return semihosting_call(SEMIHOSTING_SYS_SEEK, block) == 0 ? 0 : -1;
}

void board_file_close(int handle) {
  const uint32_t block[1] = {(uint32_t)handle};
  (void)semihosting_call(SEMIHOSTING_SYS_CLOSE, block);
}
