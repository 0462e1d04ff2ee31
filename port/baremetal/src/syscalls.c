/* Minimal newlib system calls. Deliberately NO _sbrk: newlib's malloc needs it, so any heap use
 * anywhere in a firmware image (malloc, operator new, std::vector, exceptions, stdio buffers)
 * fails to link with "undefined reference to `_sbrk'". scripts/check-no-heap.sh checks the
 * linked ELF as well. Each stub is linked only if something references it (--gc-sections). */
#include <errno.h>
#include <stddef.h>
#include <sys/stat.h>

#include "baremetal/board.h"

/* Prototypes: newlib calls these by name; declared here for -Wmissing-prototypes hygiene. */
_Noreturn void _exit(int status);
int _write(int file, const char* data, int length);
int _read(int file, char* data, int length);
int _close(int file);
int _lseek(int file, int offset, int whence);
int _fstat(int file, struct stat* status);
int _isatty(int file);
int _kill(int pid, int signal);
int _getpid(void);
_Noreturn void __assert_func(const char* file, int line, const char* function, const char* expression);

_Noreturn void _exit(int status) {
  board_exit(status);
}

/* stdout/stderr go to the semihosting console, character by character (no buffer to own). */
int _write(int file, const char* data, int length) {
  if (file != 1 && file != 2) {
    errno = EBADF;
    return -1;
  }
  for (int i = 0; i < length; ++i) board_write_char(data[i]);
  return length;
}

int _read(int file, char* data, int length) {
  (void)file;
  (void)data;
  (void)length;
  return 0; /* end of file: the firmware reads no input */
}

int _close(int file) {
  (void)file;
  errno = EBADF;
  return -1;
}

int _lseek(int file, int offset, int whence) {
  (void)file;
  (void)offset;
  (void)whence;
  return 0;
}

int _fstat(int file, struct stat* status) {
  (void)file;
  status->st_mode = S_IFCHR;
  return 0;
}

int _isatty(int file) {
  return file >= 0 && file <= 2;
}

/* abort() -> raise() -> _kill(): stop the run as a fault. */
int _kill(int pid, int signal) {
  (void)pid;
  (void)signal;
  board_write("\n*** abort()\n");
  board_exit(BOARD_EXIT_FAULT);
}

int _getpid(void) {
  return 1;
}

/* Replaces newlib's, which formats with fiprintf (stdio buffers -> malloc). Reached only by
 * assert() in builds without NDEBUG (e.g. Eigen's range checks in a Debug firmware). */
_Noreturn void __assert_func(const char* file, int line, const char* function, const char* expression) {
  (void)function;
  char digits[12];
  size_t n = 0;
  unsigned value = line < 0 ? 0u : (unsigned)line;
  do {
    digits[n++] = (char)('0' + value % 10u);
    value /= 10u;
  } while (value != 0u && n < sizeof digits);
  board_write("\n*** assert failed: ");
  board_write(file);
  board_write_char(':');
  while (n > 0) board_write_char(digits[--n]);
  board_write(": ");
  board_write(expression);
  board_write_char('\n');
  board_exit(BOARD_EXIT_FAULT);
}
