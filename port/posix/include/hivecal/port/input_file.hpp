// Input files of the hosted tools: the one place a file (or an explicit '-' for stdin) is
// opened for reading. Only regular files are read (a device such as /dev/zero, a FIFO or a
// folder is refused at once), and a file larger than the caller's limit is refused before
// any byte is read. InputFile is the library's ByteReader, so a capture is decoded straight
// from it (no adapter); text readers pull their bytes through it too.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "hivecal/port/error.hpp"
#include "hivecal/wire/byte_reader.hpp"

namespace hivecal::port {

/// Largest capture or log accepted [bytes] (days of both streams at full line rate).
inline constexpr std::uint64_t kMaxStreamInputBytes = 64ull << 30;
/// Largest small text input accepted (result JSON, calibration.conf, pose lists) [bytes].
inline constexpr std::uint64_t kMaxTextInputBytes = 256ull << 20;

/// Identity of a file: device and inode, and its canonical path (for "same file" checks).
struct FileIdentity {
  bool exists = false;       ///< the path names an existing file
  std::uint64_t device = 0;  ///< st_dev
  std::uint64_t inode = 0;   ///< st_ino
  std::string canonical;     ///< realpath (of the folder + name when the file does not exist)
};

/// The identity of `path` (symlinks followed); "" canonical when even its folder is unknown.
FileIdentity identify(const std::string& path);
/// True when both name the same file (same device and inode, or the same canonical path).
bool same_file(const FileIdentity& a, const FileIdentity& b);

/// A regular file (or stdin for "-") read from its start to its end.
class InputFile final : public ByteReader {
 public:
  InputFile() = default;
  ~InputFile();
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;

  /// Opens `path`: refused (Fault::input) unless a regular file of at most `max_bytes`, or
  /// "-" (stdin, whose length is checked as it is read).
  Error open(const std::string& path, std::uint64_t max_bytes);
  /// Next bytes; *count 0 at the end. read_failed (see error()) on a read error or when
  /// stdin passes max_bytes.
  Status read(std::uint8_t* out, std::size_t capacity, std::size_t* count) override;
  /// Closes the file (also done by the destructor).
  void close();

  const std::string& path() const { return path_; }         ///< as given
  std::uint64_t size_bytes() const { return size_bytes_; }  ///< file size [bytes]; 0 for stdin
  std::uint64_t bytes_read() const { return bytes_read_; }  ///< delivered so far [bytes]
  const Error& error() const { return error_; }             ///< why read() failed
  bool is_stdin() const { return is_stdin_; }               ///< opened as "-"

 private:
  int fd_ = -1;
  bool is_stdin_ = false;
  std::string path_;
  std::uint64_t size_bytes_ = 0;
  std::uint64_t max_bytes_ = 0;
  std::uint64_t bytes_read_ = 0;
  Error error_;
};

/// Reads a whole input (checked as by InputFile::open) into *text.
Error read_whole_file(const std::string& path, std::uint64_t max_bytes, std::string* text);

}  // namespace hivecal::port
