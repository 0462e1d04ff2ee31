#include "hivecal/port/capture_file.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <utility>

#include "hivecal/port/error.hpp"

namespace hivecal::port {

CaptureWriter::~CaptureWriter() {
  (void)close();
}

Error CaptureWriter::open(const std::string& path, bool replace) {
  path_ = path;
  bytes_written_ = 0;
  struct stat info {};
  if (replace && ::stat(path.c_str(), &info) == 0 && !S_ISREG(info.st_mode)) {
    return Error::output(quoted(path, 200) + ": not a regular file; refusing to write a capture over it");
  }
  // Never truncates an existing capture unasked; with `replace`, only once it is locked.
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | (replace ? 0 : O_EXCL) | O_CLOEXEC, 0666);
  if (fd_ < 0) {
    return Error::output(quoted(path, 200) + (errno == EEXIST
                                                  ? ": exists; refusing to overwrite a capture (--force replaces it)"
                                                  : ": cannot create: " + system_message(errno)));
  }
  // Held while recording: a second recorder of the same file (even with --force) is refused
  // instead of both writing it and one recording being lost.
  Error error;
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    error = Error::output(quoted(path, 200) + (errno == EWOULDBLOCK
                                                   ? ": another process is recording into it; refusing to replace it"
                                                   : ": cannot lock: " + system_message(errno)));
  } else if (replace && ::ftruncate(fd_, 0) != 0) {
    error = Error::output(quoted(path, 200) + ": cannot truncate: " + system_message(errno));
  }
  if (!error.ok()) {
    ::close(fd_);
    fd_ = -1;
  }
  return error;
}

Error CaptureWriter::write(const std::uint8_t* bytes, std::size_t count) {
  while (count > 0) {
    const ssize_t put = ::write(fd_, bytes, count);
    if (put < 0) {
      if (errno == EINTR) continue;
      return Error::output(path_ + ": write failed: " + std::strerror(errno));
    }
    bytes += put;
    count -= static_cast<std::size_t>(put);
    bytes_written_ += static_cast<std::uint64_t>(put);
  }
  return Error{};
}

Error CaptureWriter::write_whole(const std::uint8_t* bytes, std::size_t count) {
  const std::uint64_t before = bytes_written_;
  const Error error = write(bytes, count);
  if (error.ok() || bytes_written_ == before) return error;
  // A part went in (a full disk, `ulimit -f`): cut it off, the file ends at the last whole record.
  if (::ftruncate(fd_, static_cast<off_t>(before)) != 0) {
    return Error::output(error.message +
                         "; a part of the last record stays (cannot cut it off: " + std::strerror(errno) + ")");
  }
  bytes_written_ = before;
  return Error::output(error.message + "; the file ends at the last whole record (" + std::to_string(before) +
                       " bytes)");
}

Error CaptureWriter::sync() {
  if (fd_ >= 0 && ::fsync(fd_) != 0 && errno != EINVAL) {  // EINVAL: a pipe or tty, nothing to sync
    return Error::output(path_ + ": fsync failed: " + std::strerror(errno));
  }
  return Error{};
}

Error CaptureWriter::close() {
  if (fd_ < 0) return Error{};
  Error error = sync();
  if (::close(fd_) != 0 && error.ok()) error = Error::output(path_ + ": close failed: " + std::strerror(errno));
  fd_ = -1;
  return error;
}

CaptureFileSource::CaptureFileSource(std::string path, double pace_bytes_per_s)
    : path_(std::move(path)), pace_bytes_per_s_(pace_bytes_per_s) {}

CaptureFileSource::~CaptureFileSource() {
  if (fd_ >= 0) ::close(fd_);
}

Error CaptureFileSource::open() {
  fd_ = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) {
    return Error::input(path_ + ": cannot open: " + std::strerror(errno));
  }
  bytes_read_ = 0;
  start_ms_ = monotonic_ms();
  return Error{};
}

ReadResult CaptureFileSource::read(std::uint8_t* buffer, std::size_t capacity, int timeout_ms) {
  if (fd_ < 0) return ReadResult{ReadStatus::error, 0, EBADF};
  if (pace_bytes_per_s_ > 0.0) {
    // Bytes allowed by now; wait (up to the timeout) for at least one.
    const std::int64_t deadline_ms = monotonic_ms() + (timeout_ms > 0 ? timeout_ms : 0);
    for (;;) {
      const double elapsed_s = static_cast<double>(monotonic_ms() - start_ms_) / 1000.0;
      const double allowed = elapsed_s * pace_bytes_per_s_ - static_cast<double>(bytes_read_);
      if (allowed >= 1.0) {
        if (static_cast<double>(capacity) > allowed) capacity = static_cast<std::size_t>(allowed);
        break;
      }
      const std::int64_t now_ms = monotonic_ms();
      if (now_ms >= deadline_ms) return ReadResult{ReadStatus::timeout, 0, 0};
      const auto need_ms = static_cast<std::int64_t>((1.0 - allowed) * 1000.0 / pace_bytes_per_s_) + 1;
      sleep_ms(need_ms < deadline_ms - now_ms ? need_ms : deadline_ms - now_ms);
    }
  }
  for (;;) {
    const ssize_t got = ::read(fd_, buffer, capacity);
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) return ReadResult{ReadStatus::error, 0, errno};
    if (got == 0) return ReadResult{ReadStatus::end_of_stream, 0, 0};
    bytes_read_ += static_cast<std::uint64_t>(got);
    return ReadResult{ReadStatus::data, static_cast<std::size_t>(got), 0};
  }
}

}  // namespace hivecal::port
