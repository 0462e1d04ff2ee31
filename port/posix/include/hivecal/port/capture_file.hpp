// Capture files: the raw bytes of one port, nothing added (serial-protocol.md). The writer
// hands every chunk to the kernel at once (a killed process loses nothing it had read) and
// fsyncs on demand; the source replays a capture through the ByteSource interface,
// optionally paced at a given byte rate (a 460800 baud line carries 46080 bytes/s).
#pragma once

#include <cstdint>
#include <string>

#include "hivecal/port/byte_source.hpp"
#include "hivecal/port/error.hpp"

namespace hivecal::port {

/// Appends raw bytes to a capture file.
class CaptureWriter {
 public:
  CaptureWriter() = default;
  ~CaptureWriter();
  CaptureWriter(const CaptureWriter&) = delete;
  CaptureWriter& operator=(const CaptureWriter&) = delete;

  /// Creates `path`; an existing file is an error unless `replace` (then a regular file is
  /// truncated; a device, FIFO or folder is still refused). The file stays locked (flock)
  /// until close(): a file another writer holds is refused, never truncated. Fault::output on
  /// failure.
  Error open(const std::string& path, bool replace);
  /// Writes all `count` bytes (retrying short writes and EINTR). Fault::output on failure.
  Error write(const std::uint8_t* bytes, std::size_t count);
  /// Writes one record (a log row) whole: after a failed write the part that went in is cut
  /// off again, so the file ends at the last whole record. Fault::output on failure.
  Error write_whole(const std::uint8_t* bytes, std::size_t count);
  /// Forces the written bytes to storage (fsync).
  Error sync();
  /// sync() then close; the first failure of either. Safe to call twice.
  Error close();
  std::uint64_t bytes_written() const { return bytes_written_; }  ///< bytes handed to the kernel
  const std::string& path() const { return path_; }               ///< the file

 private:
  int fd_ = -1;
  std::string path_;
  std::uint64_t bytes_written_ = 0;
};

/// Replays a capture file as a byte source.
class CaptureFileSource final : public ByteSource {
 public:
  /// A source over `path`; `pace_bytes_per_s` > 0 delivers no faster than that rate [bytes/s].
  explicit CaptureFileSource(std::string path, double pace_bytes_per_s = 0.0);
  ~CaptureFileSource() override;
  CaptureFileSource(const CaptureFileSource&) = delete;
  CaptureFileSource& operator=(const CaptureFileSource&) = delete;

  /// Opens the file; Fault::input on failure.
  Error open();
  /// Next bytes of the file; end_of_stream at its end (timeouts only ever come from pacing).
  ReadResult read(std::uint8_t* buffer, std::size_t capacity, int timeout_ms) override;
  int poll_fd() const override { return fd_; }
  const std::string& name() const override { return path_; }
  std::uint64_t bytes_read() const { return bytes_read_; }  ///< bytes delivered so far

 private:
  std::string path_;
  double pace_bytes_per_s_;
  int fd_ = -1;
  std::uint64_t bytes_read_ = 0;
  std::int64_t start_ms_ = 0;
};

}  // namespace hivecal::port
