// A source of raw stream bytes: a serial port, or a capture file replayed through the same
// interface. Bytes only: framing and decoding live in the library.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>

namespace hivecal::port {

/// What one read() brought.
enum class ReadStatus {
  data,           ///< `bytes` > 0 bytes were read
  timeout,        ///< nothing arrived within the timeout (the source is still usable)
  end_of_stream,  ///< a capture file is exhausted (never for serial ports)
  disconnected,   ///< the device is gone; later reads try to reopen it
  error,          ///< a permanent error (see error_number)
};

/// Outcome of one read().
struct ReadResult {
  ReadStatus status = ReadStatus::timeout;  ///< what happened
  std::size_t bytes = 0;                    ///< bytes stored in the buffer
  int error_number = 0;                     ///< errno of the failure, 0 otherwise
};

/// Reads raw bytes with a timeout.
class ByteSource {
 public:
  virtual ~ByteSource() = default;
  /// Reads up to `capacity` bytes into `buffer`, waiting at most `timeout_ms` [ms] for the
  /// first one (0: do not wait). Signals (EINTR) never end a wait early.
  virtual ReadResult read(std::uint8_t* buffer, std::size_t capacity, int timeout_ms) = 0;
  /// File descriptor to poll() for readability, or -1 while none is open.
  virtual int poll_fd() const = 0;
  /// Path or name, for messages.
  virtual const std::string& name() const = 0;
};

/// Milliseconds of a monotonic clock (for timeouts and pacing).
std::int64_t monotonic_ms();
/// Sleeps `ms` milliseconds, resuming after signals.
void sleep_ms(std::int64_t ms);
/// Sleeps `ms` milliseconds or until *stop is set (checked at least every 100 ms); false
/// when stopped.
bool sleep_ms(std::int64_t ms, const std::atomic<bool>& stop);

}  // namespace hivecal::port
