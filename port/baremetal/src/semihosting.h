/* ARM semihosting calls (Arm "Semihosting for AArch32 and AArch64", v2). Internal to the port. */
#ifndef HIVECAL_BAREMETAL_SEMIHOSTING_H
#define HIVECAL_BAREMETAL_SEMIHOSTING_H

#include <stdint.h>

enum {
  SEMIHOSTING_SYS_OPEN = 0x01,
  SEMIHOSTING_SYS_CLOSE = 0x02,
  SEMIHOSTING_SYS_WRITEC = 0x03,
  SEMIHOSTING_SYS_WRITE0 = 0x04,
  SEMIHOSTING_SYS_READ = 0x06,
  SEMIHOSTING_SYS_SEEK = 0x0A,
  SEMIHOSTING_SYS_GET_CMDLINE = 0x15,
  SEMIHOSTING_SYS_EXIT = 0x18,
  SEMIHOSTING_SYS_EXIT_EXTENDED = 0x20,
};

/* Reason code of SYS_EXIT[_EXTENDED] meaning "the application exited". */
#define SEMIHOSTING_ADP_STOPPED_APPLICATION_EXIT 0x20026u

/* Performs semihosting operation `op` with parameter `arg` (a value or a block address). */
intptr_t semihosting_call(uint32_t op, const void* arg);

#endif
