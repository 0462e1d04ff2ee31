// The two passes of the stream path over a robot and a tracker stream of records: records ->
// ClockEstimator (pass 1), then the records again -> SampleExtractor in robot-clock order
// (pass 2). Records come through RecordReader: decoded from bytes (FrameRecordReader over a
// ByteReader: captures in a file, in flash, or replayed) or parsed from text logs by the
// application, so the same code serves the command-line tool and firmware. No heap: each
// stream is decoded a slice at a time into a queue of a few records.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/sync/clock_sync.hpp"
#include "hivecal/wire/byte_reader.hpp"
#include "hivecal/wire/codec.hpp"
#include "hivecal/sync/sample_extraction.hpp"
#include "hivecal/core/status.hpp"
#include "hivecal/core/types.hpp"

namespace hivecal {

/// One record of a stream, as a RecordReader gives it.
struct StreamRecord {
  /// What the record holds.
  enum class Kind : std::uint8_t {
    end,            ///< the stream is over (no record)
    joint_state,    ///< `joint` is set
    tracker_point,  ///< `point` is set
  };
  Kind kind = Kind::end;     ///< which member is set
  JointStateRecord joint;    ///< when kind is joint_state
  TrackerPointRecord point;  ///< when kind is tracker_point
};

/// A stream of records read from its start to its end: frames decoded from bytes
/// (FrameRecordReader), or rows of a text log parsed by the application.
class RecordReader {
 public:
  /// The next record (kind end once the stream is over). Errors: read_failed.
  virtual Status next(StreamRecord* record) = 0;
  /// Counters of what was read so far (a log counts its rows as frames of their type).
  virtual const DecoderStats& counters() const = 0;

 protected:
  RecordReader() = default;
  RecordReader(const RecordReader&) = default;
  RecordReader& operator=(const RecordReader&) = default;
  ~RecordReader() = default;
};

/// Records decoded from a byte stream, a slice at a time into a queue of a few records.
class FrameRecordReader final : public RecordReader, private FrameHandler {
 public:
  /// A reader decoding `bytes` (not owned), from its current position.
  explicit FrameRecordReader(ByteReader* bytes) : bytes_(bytes) {}
  Status next(StreamRecord* record) override;
  const DecoderStats& counters() const override { return decoder_.stats(); }

  static constexpr std::size_t kChunkBytes = 256;  ///< bytes read from the ByteReader at a time
  static constexpr std::size_t kSliceBytes = 128;  ///< bytes fed to the decoder at a time
  static constexpr std::size_t kQueueRecords = 4;  ///< records a slice can complete, at most

 private:
  void on_joint_state(const JointStateRecord& record) override;
  void on_tracker_point(const TrackerPointRecord& record) override;
  void push(const StreamRecord& record);

  ByteReader* bytes_;
  StreamDecoder decoder_;
  std::uint8_t chunk_[kChunkBytes] = {};
  std::size_t chunk_size_ = 0;
  std::size_t chunk_position_ = 0;
  bool ended_ = false;
  StreamRecord queue_[kQueueRecords];
  std::size_t queue_first_ = 0;
  std::size_t queue_size_ = 0;
};

/// Counters of one pass over the two streams.
struct StreamPassStats {
  DecoderStats robot_decoder;    ///< frames (or log rows) of the robot stream
  DecoderStats tracker_decoder;  ///< frames (or log rows) of the tracker stream
};

/// Pass 1: every record of both streams (robot stream first, then tracker) into `estimator`,
/// then estimator->estimate(fit). Returns the estimate's status, or read_failed (a reader
/// failed; nothing estimated). *stats may be null.
Status estimate_clock_from_streams(RecordReader& robot, RecordReader& tracker, ClockEstimatorBase* estimator,
                                   ClockFit* fit, StreamPassStats* stats);
/// Pass 1 over two byte streams (decoded with FrameRecordReader).
Status estimate_clock_from_streams(ByteReader& robot, ByteReader& tracker, ClockEstimatorBase* estimator, ClockFit* fit,
                                   StreamPassStats* stats);

/// Pass 2: both streams merged in robot-clock order (through extractor->clock()) into
/// `extractor`, then finish(). Tracker records in the robot stream and robot records in the
/// tracker stream are ignored. Returns ok, dataset_full (some quasi-static points did not
/// fit), or read_failed. *stats may be null.
Status extract_samples_from_streams(RecordReader& robot, RecordReader& tracker, SampleExtractorBase* extractor,
                                    StreamPassStats* stats);
/// Pass 2 over two byte streams (decoded with FrameRecordReader).
Status extract_samples_from_streams(ByteReader& robot, ByteReader& tracker, SampleExtractorBase* extractor,
                                    StreamPassStats* stats);

}  // namespace hivecal
