/* The bare-metal board interface the firmware images use: semihosting console, exit with a
 * status, the semihosting command line, and stack measurement. C so that the startup code
 * (which calls main, forbidden in C++) and C++ images share it. Nothing here is used by lib/. */
#ifndef HIVECAL_BAREMETAL_BOARD_H
#define HIVECAL_BAREMETAL_BOARD_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Exit statuses seen by the host (qemu-system-arm returns them; scripts/run-qemu-mps2.sh too).
 * main's return value is passed through as is; the images return 0 or 1. */
enum {
  BOARD_EXIT_OK = 0,     /* main returned 0 */
  BOARD_EXIT_FAILED = 1, /* main of the images returns this for failed checks */
  BOARD_EXIT_FAULT = 2,  /* a fault handler, assert() or abort() ended the run */
};

/* Writes a NUL-terminated string to the host console (SYS_WRITE0). */
void board_write(const char* text);
/* Writes one character to the host console (SYS_WRITEC). */
void board_write_char(char c);
/* Ends the emulation with `status` as the host process exit code (SYS_EXIT_EXTENDED). */
__attribute__((noreturn)) void board_exit(int status);
/* The arguments after the program name passed with -semihosting-config arg=... ("" if none). */
const char* board_command_line(void);

/* Host files through semihosting (SYS_OPEN, SYS_READ, SYS_SEEK, SYS_CLOSE), read-only and
 * binary: test data such as recorded captures (a product reads its UARTs instead). */
/* Opens `path` (relative to QEMU's working directory) for reading; a handle >= 0, or -1. */
int board_file_open(const char* path);
/* Reads up to `capacity` bytes; the bytes read (0 at the end of the file), or -1 on error. */
long board_file_read(int handle, void* out, size_t capacity);
/* Back to the first byte; 0, or -1 on error. */
int board_file_rewind(int handle);
/* Closes the handle. */
void board_file_close(int handle);

/* Size of the stack region reserved by the linker script [bytes]. */
size_t board_stack_size_bytes(void);
/* Deepest stack use since reset, from the paint pattern left untouched [bytes]. */
size_t board_stack_used_bytes(void);

#ifdef __cplusplus
}
#endif

#endif
