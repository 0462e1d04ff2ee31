// POSIX serial port in raw mode (termios), read with poll() and a timeout. A device that
// disappears (USB unplugged, pty master closed) is closed and reopened with exponential
// backoff on later reads, so a recording survives a cable pulled for a moment.
#pragma once

#include <cstdint>
#include <string>

#include "hivecal/port/byte_source.hpp"
#include "hivecal/port/error.hpp"

namespace hivecal::port {

/// Baud rate of the robot joint-state link (serial-protocol.md) [bit/s].
inline constexpr int kRobotBaud = 460800;
/// Baud rate of the tracker link [bit/s].
inline constexpr int kTrackerBaud = 115200;

/// How to open and keep a serial port.
struct SerialOptions {
  std::string path;          ///< device path (a symlink such as /dev/serial/by-id/... is followed at each open)
  int baud = kRobotBaud;     ///< line rate [bit/s]; 8N1, no flow control
  int reopen_min_ms = 50;    ///< first wait before reopening a lost device [ms]
  int reopen_max_ms = 2000;  ///< longest wait between reopen attempts [ms]
};

/// True for the baud rates termios can set here (9600 .. 921600).
bool baud_supported(int baud);
/// Those rates for a message: "9600, 19200, ... or 921600".
std::string supported_bauds();

/// A serial port (or any tty, e.g. a pseudo-terminal) read as a byte stream.
class SerialPort final : public ByteSource {
 public:
  /// A closed port; open() opens it.
  explicit SerialPort(SerialOptions options);
  ~SerialPort() override;
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;

  /// Opens and configures the device (raw 8N1 at options.baud); Fault::input if it cannot be
  /// opened or configured now.
  Error open();
  /// Reads what is there (see ByteSource). On hangup or a vanished device the port is
  /// closed and `disconnected` returned; later reads reopen it when the backoff allows.
  ReadResult read(std::uint8_t* buffer, std::size_t capacity, int timeout_ms) override;
  int poll_fd() const override { return fd_; }
  const std::string& name() const override { return options_.path; }
  /// Closes the device (reads will try to reopen it).
  void close();

  bool is_open() const { return fd_ >= 0; }                   ///< a descriptor is open
  std::uint64_t reconnects() const { return reconnects_; }    ///< successful reopens after a loss
  std::uint64_t disconnects() const { return disconnects_; }  ///< losses seen

 private:
  Error configure();
  void lose();
  bool try_reopen(std::int64_t now_ms);

  SerialOptions options_;
  int fd_ = -1;
  bool ever_opened_ = false;
  std::int64_t next_reopen_ms_ = 0;
  int backoff_ms_ = 0;
  std::uint64_t reconnects_ = 0;
  std::uint64_t disconnects_ = 0;
};

}  // namespace hivecal::port
