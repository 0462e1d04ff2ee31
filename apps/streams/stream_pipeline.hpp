// Wires port/ and the text formats to lib/ for the stream path: each input is a serial
// capture (port::ByteSource -> lib FrameRecordReader) or a CSV log (LogRecordReader), then
// the library's two passes (hivecal/capture_pipeline.hpp: ClockEstimator, then
// SampleExtractor in robot-clock order) -> dataset. Memory stays bounded: records are read
// a chunk or a row at a time.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <string>

#include "csv.hpp"
#include "hivecal/sync/capture_pipeline.hpp"
#include "hivecal/sync/clock_sync.hpp"
#include "hivecal/wire/codec.hpp"
#include "hivecal/port/byte_source.hpp"
#include "hivecal/sync/sample_extraction.hpp"

namespace hivecal::streams {

/// Decodes bytes obtained elsewhere (e.g. a recorder's tap) into queues of records.
class RecordQueue final : public FrameHandler {
 public:
  std::deque<JointStateRecord>& joints() { return joints_; }      ///< decoded robot records
  std::deque<TrackerPointRecord>& points() { return points_; }    ///< decoded tracker records
  const DecoderStats& decoder_stats() const { return decoder_.stats(); }  ///< frame counters
  /// Decodes `count` bytes into the queues.
  void feed(const std::uint8_t* bytes, std::size_t count) { decoder_.feed(bytes, count, *this); }

  void on_joint_state(const JointStateRecord& record) override { joints_.push_back(record); }
  void on_tracker_point(const TrackerPointRecord& record) override { points_.push_back(record); }

 private:
  StreamDecoder decoder_;
  std::deque<JointStateRecord> joints_;
  std::deque<TrackerPointRecord> points_;
};

/// A port::ByteSource as the library's ByteReader: waits through read timeouts, keeps the
/// error text of a failed read, counts bytes.
class SourceReader final : public ByteReader {
 public:
  /// A reader over `source` (not owned).
  explicit SourceReader(port::ByteSource* source) : source_(source) {}
  Status read(std::uint8_t* out, std::size_t capacity, std::size_t* count) override;
  const std::string& error() const { return error_; }  ///< what failed, if a read did
  std::uint64_t bytes_read() const { return bytes_; }  ///< [bytes]

 private:
  port::ByteSource* source_;
  std::string error_;
  std::uint64_t bytes_ = 0;
};

/// Records of a CSV log of io-formats.md (robot `t,q1..q6` or tracker `t,x,y,z[,status]`),
/// one row per record. Seconds become whole microseconds; a log has no sequence numbers,
/// velocities or currents (they stay 0, nothing downstream uses them).
class LogRecordReader final : public RecordReader {
 public:
  /// Which log the file holds.
  enum class Kind { robot, tracker };
  /// A reader of the log at `path`, opened by the first next().
  LogRecordReader(Kind kind, std::string path) : kind_(kind), path_(std::move(path)) {}
  Status next(StreamRecord* record) override;
  const DecoderStats& counters() const override { return stats_; }
  const std::string& error() const { return error_; }  ///< parse error (file:line: what), if any
  std::uint64_t bytes_read() const { return kind_ == Kind::robot ? robot_.bytes_read() : tracker_.bytes_read(); }

 private:
  Status fail(const std::string& problem);
  bool to_microseconds(double t_s, std::uint64_t* t_us);

  Kind kind_;
  std::string path_;
  bool opened_ = false;
  textio::RobotLogReader robot_;
  textio::TrackerLogReader tracker_;
  DecoderStats stats_;
  std::uint64_t last_us_ = 0;
  std::string error_;
};

/// Told how far a pass over the two inputs is: pass 1 (clock) or 2 (samples), bytes read of
/// both inputs so far and in all (0 when unknown) [bytes]. Called about every 256 kB read, and
/// once at the end of each pass.
using PassProgress = std::function<void(int pass, std::uint64_t bytes_done, std::uint64_t bytes_total)>;

/// Counters of one pass over the two streams.
using PassStats = StreamPassStats;

/// Everything a two-pass run over two files reports.
struct CaptureRunReport {
  Status clock_status = Status::ok;       ///< outcome of the clock estimation
  ClockFit clock;                          ///< the clock relation (when clock_status is ok)
  ClockProfileStats clock_stats;           ///< what went into the clock profiles
  PassStats decoding;                      ///< frame counters (first pass)
  bool robot_is_log = false;               ///< the robot input was a CSV log (counters are rows)
  bool tracker_is_log = false;             ///< the tracker input was a CSV log (counters are rows)
  Status extraction_status = Status::ok;  ///< ok or dataset_full
  ExtractionCounts counts;                 ///< kept / dropped per reason
};

/// Both passes over two files into `dataset`; each is a serial capture or a CSV log
/// (detected by content, so the two may differ). False with a message when a file cannot be
/// read or parsed; a failed clock fit is reported in *report (no extraction then).
bool extract_from_files(const std::string& robot_path, const std::string& tracker_path,
                        const ClockSyncConfig& clock_config, const ExtractionConfig& extraction_config,
                        DatasetBase* dataset, CaptureRunReport* report, std::string* error,
                        ExtractionObserver* observer = nullptr, const PassProgress& progress = {});

}  // namespace hivecal::streams
