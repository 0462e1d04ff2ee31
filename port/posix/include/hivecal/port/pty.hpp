// Pseudo-terminal pairs (posix_openpt): the simulator writes a device's bytes into the
// master side, and a SerialPort reads them from the slave path like from a real tty.
#pragma once

#include <atomic>
#include <string>

#include "hivecal/port/error.hpp"

namespace hivecal::port {

/// An open pseudo-terminal.
struct PtyPair {
  int master_fd = -1;      ///< written by the simulated device
  int slave_fd = -1;       ///< kept open so the slave stays configured (raw) between readers
  std::string slave_path;  ///< e.g. /dev/pts/3: what the reader opens
};

/// Opens a pty pair with the slave in raw mode (no echo, no line editing, 8-bit clean).
Error open_pty(PtyPair* pty);
/// Closes both sides (the reader of the slave sees a hangup).
void close_pty(PtyPair* pty);
/// Writes all `count` bytes to `fd`, retrying short writes and EINTR. False on error, or
/// as soon as *stop is set (checked at least every 100 ms while the writer waits for room).
bool write_all(int fd, const void* bytes, std::size_t count, const std::atomic<bool>* stop = nullptr);

}  // namespace hivecal::port
