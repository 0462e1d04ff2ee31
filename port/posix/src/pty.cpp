#include "hivecal/port/pty.hpp"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

namespace hivecal::port {

Error open_pty(PtyPair* pty) {
  close_pty(pty);
  pty->master_fd = posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
  char name[128] = {};
  if (pty->master_fd < 0 || grantpt(pty->master_fd) != 0 || unlockpt(pty->master_fd) != 0 ||
      ptsname_r(pty->master_fd, name, sizeof name) != 0) {
    close_pty(pty);
    return Error::failure(std::string("cannot open a pseudo-terminal: ") + std::strerror(errno));
  }
  pty->slave_path = name;
  pty->slave_fd = ::open(name, O_RDWR | O_NOCTTY | O_CLOEXEC);
  termios tio{};
  if (pty->slave_fd < 0 || tcgetattr(pty->slave_fd, &tio) != 0) {
    close_pty(pty);
    return Error::failure(pty->slave_path + ": cannot open: " + std::strerror(errno));
  }
  cfmakeraw(&tio);  // no echo back into the master, no line editing, 8-bit clean
  if (tcsetattr(pty->slave_fd, TCSANOW, &tio) != 0) {
    close_pty(pty);
    return Error::failure(pty->slave_path + ": cannot configure: " + std::strerror(errno));
  }
  return Error{};
}

void close_pty(PtyPair* pty) {
  if (pty->master_fd >= 0) ::close(pty->master_fd);
  if (pty->slave_fd >= 0) ::close(pty->slave_fd);
  pty->master_fd = -1;
  pty->slave_fd = -1;
}

bool write_all(int fd, const void* bytes, std::size_t count, const std::atomic<bool>* stop) {
  const auto* p = static_cast<const std::uint8_t*>(bytes);
  while (count > 0) {
    if (stop != nullptr && stop->load()) return false;
    // Wait for room in slices, so that a stop request is seen even when no reader drains
    // the other side (a pty whose reader left blocks its writer forever).
    pollfd room{fd, POLLOUT, 0};
    const int ready = ::poll(&room, 1, stop != nullptr ? 100 : -1);
    if (ready < 0 && errno != EINTR) return false;
    if (ready <= 0) continue;
    const ssize_t put = ::write(fd, p, count);
    if (put < 0) {
      if (errno == EINTR || errno == EAGAIN) continue;
      return false;
    }
    p += put;
    count -= static_cast<std::size_t>(put);
  }
  return true;
}

}  // namespace hivecal::port
