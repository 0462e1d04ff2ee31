// The two passes of the stream path over a robot and a tracker byte stream (captures in a
// file, in flash, or replayed): decode -> ClockEstimator (pass 1), then decode again ->
// SampleExtractor in robot-clock order (pass 2). The bytes come through ByteReader, so the
// same code serves the command-line tool (files) and firmware (flash, semihosting). No heap:
// each stream is decoded a slice at a time into a queue of a few records.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/clock_sync.hpp"
#include "hivecal/codec.hpp"
#include "hivecal/sample_extraction.hpp"
#include "hivecal/status.hpp"
#include "hivecal/types.hpp"

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

/// Decoder counters of one pass over the two streams.
struct StreamPassStats {
  DecoderStats robot_decoder;    ///< frames of the robot stream
  DecoderStats tracker_decoder;  ///< frames of the tracker stream
};

/// Pass 1: every record of both streams (robot stream first, then tracker) into `estimator`,
/// then estimator->estimate(fit). Returns the estimate's status, or read_failed (a reader
/// failed; nothing estimated). *stats may be null.
Status estimate_clock_from_streams(ByteReader& robot, ByteReader& tracker, ClockEstimatorBase* estimator,
                                   ClockFit* fit, StreamPassStats* stats);

/// Pass 2: both streams merged in robot-clock order (through extractor->clock()) into
/// `extractor`, then finish(). Tracker records in the robot stream and robot records in the
/// tracker stream are ignored. Returns ok, dataset_full (some quasi-static points did not
/// fit), or read_failed. *stats may be null.
Status extract_samples_from_streams(ByteReader& robot, ByteReader& tracker, SampleExtractorBase* extractor,
                                    StreamPassStats* stats);

}  // namespace hivecal
