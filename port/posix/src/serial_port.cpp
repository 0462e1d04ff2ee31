#include "hivecal/port/serial_port.hpp"

#include <fcntl.h>
#include <iterator>
#include <sys/file.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <utility>

namespace hivecal::port {
namespace {

/// The rates termios sets here, with their constants.
constexpr struct {
  int baud;
  speed_t speed;
} kBauds[] = {{9600, B9600},     {19200, B19200},   {38400, B38400},   {57600, B57600},
              {115200, B115200}, {230400, B230400}, {460800, B460800}, {921600, B921600}};

bool baud_constant(int baud, speed_t* speed) {
  for (const auto& b : kBauds) {
    if (b.baud != baud) continue;
    *speed = b.speed;
    return true;
  }
  return false;
}

/// errno values that mean the device itself is gone (unplugged, pty master closed).
bool device_lost(int error_number) {
  return error_number == EIO || error_number == ENXIO || error_number == ENODEV || error_number == EBADF ||
         error_number == ENOENT;
}

}  // namespace

bool baud_supported(int baud) {
  speed_t speed = 0;
  return baud_constant(baud, &speed);
}

std::string supported_bauds() {
  std::string text;
  for (const auto& b : kBauds) {
    text += (text.empty() ? "" : &b == &kBauds[std::size(kBauds) - 1] ? " or " : ", ") + std::to_string(b.baud);
  }
  return text;
}

SerialPort::SerialPort(SerialOptions options) : options_(std::move(options)) {}

SerialPort::~SerialPort() {
  close();
}

void SerialPort::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

Error SerialPort::open() {
  close();
  speed_t speed = 0;
  if (!baud_constant(options_.baud, &speed)) {
    return Error::input(options_.path + ": unsupported baud rate " + std::to_string(options_.baud));
  }
  fd_ = ::open(options_.path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) {
    return Error::input(options_.path + ": cannot open: " + std::strerror(errno));
  }
  // One reader per port: a second recorder (or the same port given twice) would split the
  // bytes between two unusable captures. An advisory lock, as serial tools take them.
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    close();
    return Error::input(options_.path + ": in use by another reader (" +
                        (error == EWOULDBLOCK ? std::string("locked") : std::string(std::strerror(error))) + ")");
  }
  Error configured = configure();
  if (!configured.ok()) {
    close();
    return configured;
  }
  ever_opened_ = true;
  backoff_ms_ = 0;
  return Error{};
}

// Raw 8N1: no echo, no line discipline, no flow control, reads return at once (poll waits).
Error SerialPort::configure() {
  termios tio{};
  if (tcgetattr(fd_, &tio) != 0) {
    return Error::input(options_.path + ": not a terminal: " + std::strerror(errno));
  }
  cfmakeraw(&tio);
  tio.c_cflag |= CLOCAL | CREAD;
  tio.c_cflag &= ~static_cast<tcflag_t>(CSTOPB | PARENB | CRTSCTS);
  tio.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY);
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  speed_t speed = 0;
  (void)baud_constant(options_.baud, &speed);
  if (cfsetispeed(&tio, speed) != 0 || cfsetospeed(&tio, speed) != 0 || tcsetattr(fd_, TCSANOW, &tio) != 0) {
    return Error::input(options_.path + ": cannot configure: " + std::strerror(errno));
  }
  return Error{};
}

void SerialPort::lose() {
  close();
  ++disconnects_;
  backoff_ms_ = options_.reopen_min_ms;
  next_reopen_ms_ = monotonic_ms() + backoff_ms_;
}

bool SerialPort::try_reopen(std::int64_t now_ms) {
  if (now_ms < next_reopen_ms_) return false;
  if (open().ok()) {  // a failed retry is not an error: the backoff grows
    ++reconnects_;
    return true;
  }
  backoff_ms_ = backoff_ms_ * 2 > options_.reopen_max_ms ? options_.reopen_max_ms : backoff_ms_ * 2;
  if (backoff_ms_ <= 0) backoff_ms_ = options_.reopen_min_ms;
  next_reopen_ms_ = now_ms + backoff_ms_;
  return false;
}

ReadResult SerialPort::read(std::uint8_t* buffer, std::size_t capacity, int timeout_ms) {
  const std::int64_t deadline_ms = monotonic_ms() + (timeout_ms > 0 ? timeout_ms : 0);
  for (;;) {
    const std::int64_t now_ms = monotonic_ms();
    if (fd_ < 0 && !try_reopen(now_ms)) {
      // Wait for the next reopen attempt or the deadline, whichever comes first.
      if (now_ms >= deadline_ms) return ReadResult{ReadStatus::disconnected, 0, 0};
      sleep_ms((next_reopen_ms_ < deadline_ms ? next_reopen_ms_ : deadline_ms) - now_ms);
      continue;
    }
    pollfd pfd{fd_, POLLIN, 0};
    const std::int64_t wait_ms = deadline_ms > now_ms ? deadline_ms - now_ms : 0;
    const int ready = ::poll(&pfd, 1, static_cast<int>(wait_ms));
    if (ready < 0) {
      if (errno == EINTR) continue;  // a signal: wait for the rest of the timeout
      return ReadResult{ReadStatus::error, 0, errno};
    }
    if (ready == 0) return ReadResult{ReadStatus::timeout, 0, 0};
    if ((pfd.revents & POLLIN) != 0) {
      const ssize_t got = ::read(fd_, buffer, capacity);
      if (got > 0) return ReadResult{ReadStatus::data, static_cast<std::size_t>(got), 0};
      if (got < 0 && (errno == EINTR || errno == EAGAIN)) continue;
      const int error_number = got < 0 ? errno : 0;
      if (got < 0 && !device_lost(error_number)) return ReadResult{ReadStatus::error, 0, error_number};
      lose();  // 0 bytes after POLLIN (hangup) or the device vanished
      return ReadResult{ReadStatus::disconnected, 0, error_number};
    }
    lose();  // POLLHUP / POLLERR / POLLNVAL without data
    return ReadResult{ReadStatus::disconnected, 0, 0};
  }
}

}  // namespace hivecal::port
