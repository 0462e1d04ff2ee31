// Where stream bytes come from: a capture file, a serial port, flash, a test buffer. The one
// byte abstraction of the library; the port layer implements it for files and devices.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/core/span.hpp"
#include "hivecal/core/status.hpp"

namespace hivecal {

/// A source of stream bytes, read from its start to its end.
class ByteReader {
 public:
  /// Reads up to `capacity` bytes into `out`; *count = bytes read, 0 only at the end of the
  /// stream (a reader waits for data rather than return 0 early). Errors: read_failed.
  virtual Status read(std::uint8_t* out, std::size_t capacity, std::size_t* count) = 0;

 protected:
  ByteReader() = default;
  ByteReader(const ByteReader&) = default;
  ByteReader& operator=(const ByteReader&) = default;
  ~ByteReader() = default;
};

/// Bytes already in memory (a capture linked into flash, a test buffer).
class MemoryByteReader final : public ByteReader {
 public:
  /// A reader over `bytes` (not owned), positioned at the start.
  explicit MemoryByteReader(Span<const std::uint8_t> bytes) : bytes_(bytes) {}
  Status read(std::uint8_t* out, std::size_t capacity, std::size_t* count) override;
  /// Back to the first byte (the second pass reads the stream again).
  void rewind() { position_ = 0; }

 private:
  Span<const std::uint8_t> bytes_;
  std::size_t position_ = 0;
};

}  // namespace hivecal
