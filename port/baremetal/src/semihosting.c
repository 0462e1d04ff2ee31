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

void board_write(const char* text) { (void)semihosting_call(SEMIHOSTING_SYS_WRITE0, text); }

void board_write_char(char c) { (void)semihosting_call(SEMIHOSTING_SYS_WRITEC, &c); }

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
