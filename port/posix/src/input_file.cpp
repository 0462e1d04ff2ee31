#include "hivecal/port/input_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdlib>

namespace hivecal::port {
namespace {

/// realpath() as a string, "" when it fails.
std::string real_path(const std::string& path) {
  char* resolved = ::realpath(path.c_str(), nullptr);
  if (resolved == nullptr) return "";
  std::string out = resolved;
  std::free(resolved);
  return out;
}

std::string describe_type(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISREG(mode)) return "a regular file";
  return "a special file";
}

std::string mib(std::uint64_t bytes) {
  return std::to_string(bytes >> 20) + " MiB";
}

}  // namespace

FileIdentity identify(const std::string& path) {
  FileIdentity id;
  struct stat info {};
  if (::stat(path.c_str(), &info) == 0) {
    id.exists = true;
    id.device = static_cast<std::uint64_t>(info.st_dev);
    id.inode = static_cast<std::uint64_t>(info.st_ino);
    id.canonical = real_path(path);
    return id;
  }
  const std::size_t slash = path.find_last_of('/');
  const std::string folder = slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
  const std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  const std::string real_folder = real_path(folder);
  if (!real_folder.empty()) id.canonical = real_folder + (real_folder == "/" ? "" : "/") + name;
  return id;
}

bool same_file(const FileIdentity& a, const FileIdentity& b) {
  if (a.exists && b.exists) return a.device == b.device && a.inode == b.inode;
  return !a.canonical.empty() && a.canonical == b.canonical;
}

InputFile::~InputFile() {
  close();
}

void InputFile::close() {
  if (fd_ >= 0 && !is_stdin_) ::close(fd_);
  fd_ = -1;
}

Error InputFile::open(const std::string& path, std::uint64_t max_bytes) {
  close();
  path_ = path;
  max_bytes_ = max_bytes;
  bytes_read_ = 0;
  size_bytes_ = 0;
  error_ = Error{};
  is_stdin_ = path == "-";
  if (is_stdin_) {
    fd_ = STDIN_FILENO;
    return Error{};
  }
  const std::string name = quoted(path, 200);
  if (path.empty()) return Error::usage("empty input path");
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);  // a FIFO must not block the open
  if (fd < 0) return Error::input(name + ": cannot open: " + system_message(errno));
  struct stat info {};
  if (::fstat(fd, &info) != 0) {
    const int saved = errno;
    ::close(fd);
    return Error::input(name + ": cannot stat: " + system_message(saved));
  }
  if (!S_ISREG(info.st_mode)) {
    ::close(fd);
    return Error::input(name + ": is " + describe_type(info.st_mode) + ", not a regular file");
  }
  const auto size = static_cast<std::uint64_t>(info.st_size);
  if (size > max_bytes) {
    ::close(fd);
    return Error::input(name + ": " + mib(size) + ", more than the " + mib(max_bytes) + " accepted for this input");
  }
  const int flags = ::fcntl(fd, F_GETFL);
  if (flags >= 0) (void)::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
  fd_ = fd;
  size_bytes_ = size;
  return Error{};
}

Status InputFile::read(std::uint8_t* out, std::size_t capacity, std::size_t* count) {
  *count = 0;
  if (!error_.ok()) return Status::read_failed;
  if (fd_ < 0) {
    error_ = Error::input(quoted(path_, 200) + ": read before open");
    return Status::read_failed;
  }
  for (;;) {
    const ssize_t got = ::read(fd_, out, capacity);
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) {
      error_ = Error::input(quoted(path_, 200) + ": read failed: " + system_message(errno));
      return Status::read_failed;
    }
    bytes_read_ += static_cast<std::uint64_t>(got);
    if (bytes_read_ > max_bytes_) {  // stdin, or a file that grows while read
      error_ = Error::input(quoted(path_, 200) + ": more than the " + mib(max_bytes_) + " accepted for this input");
      return Status::read_failed;
    }
    *count = static_cast<std::size_t>(got);
    return Status::ok;
  }
}

Error read_whole_file(const std::string& path, std::uint64_t max_bytes, std::string* text) {
  InputFile file;
  Error error = file.open(path, max_bytes);
  if (!error.ok()) return error;
  text->clear();
  text->reserve(static_cast<std::size_t>(file.size_bytes()));
  std::uint8_t buffer[65536];
  std::size_t got = 0;
  do {
    if (file.read(buffer, sizeof buffer, &got) != Status::ok) return file.error();
    text->append(reinterpret_cast<const char*>(buffer), got);
  } while (got > 0);
  return Error{};
}

}  // namespace hivecal::port
