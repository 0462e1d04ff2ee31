// Wires port/ and the text formats to lib/ for the stream path: each input is a serial
// capture (port::ByteSource -> lib FrameRecordReader) or a log (textio/logs.hpp, read whole,
// served by LogRecordReader), then
// the library's two passes (hivecal/capture_pipeline.hpp: ClockEstimator, then
// SampleExtractor in robot-clock order) -> dataset. A capture's memory stays bounded (read a
// chunk at a time); a log's records are held (~136 B a robot row: 41 MB for 10 min at 500 Hz).
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <string>

#include "hivecal/port/byte_source.hpp"
#include "hivecal/sync/capture_pipeline.hpp"
#include "hivecal/sync/clock_sync.hpp"
#include "hivecal/sync/sample_extraction.hpp"
#include "hivecal/wire/codec.hpp"
#include "logs.hpp"

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

/// Records of a log read whole (textio::read_robot_log / read_tracker_log: hivecal CSV, UR
/// RTDE, rostopic, ROS 2 bag, tracker exports), served in order. A log has no sequence
/// gaps, velocities or currents (they stay 0, nothing downstream uses them); it counts its
/// records as frames of their type.
class LogRecordReader final : public RecordReader {
 public:
  /// Serves `log`'s records (not owned; must outlive the reader).
  explicit LogRecordReader(const textio::RobotLog* log) : joints_(&log->records), bytes_(log->bytes_read) {}
  /// Serves `log`'s records (not owned; must outlive the reader).
  explicit LogRecordReader(const textio::TrackerLog* log) : points_(&log->records), bytes_(log->bytes_read) {}
  Status next(StreamRecord* record) override;
  const DecoderStats& counters() const override { return stats_; }
  /// The log's bytes in proportion to the records served so far [bytes].
  std::uint64_t bytes_read() const;

 private:
  const std::vector<JointStateRecord>* joints_ = nullptr;
  const std::vector<TrackerPointRecord>* points_ = nullptr;
  std::uint64_t bytes_ = 0;
  std::size_t next_ = 0;
  DecoderStats stats_;
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
  bool robot_is_log = false;               ///< the robot input was a log (counters are records)
  bool tracker_is_log = false;             ///< the tracker input was a log (counters are records)
  textio::LogFormat robot_format = textio::LogFormat::unknown;    ///< the robot log's format
  textio::LogFormat tracker_format = textio::LogFormat::unknown;  ///< the tracker log's format
  textio::LogCounters robot_log;           ///< rows of the robot log, dropped per reason
  textio::LogCounters tracker_log;         ///< rows of the tracker log, dropped per reason
  Status extraction_status = Status::ok;  ///< ok or dataset_full
  ExtractionCounts counts;                 ///< kept / dropped per reason
};

/// Both passes over two files into `dataset`; each is a serial capture or a log (detected by
/// content, so the two may differ; a log is read once, whole). False with a message when a
/// file cannot be read or parsed, or when a capture holds only the other stream's frames; a
/// failed clock fit is reported in *report (no extraction then). `log_options`: how to read
/// a robot log (joint names of ROS logs).
bool extract_from_files(const std::string& robot_path, const std::string& tracker_path,
                        const ClockSyncConfig& clock_config, const ExtractionConfig& extraction_config,
                        DatasetBase* dataset, CaptureRunReport* report, std::string* error,
                        ExtractionObserver* observer = nullptr, const PassProgress& progress = {},
                        const textio::RobotLogOptions& log_options = {});

}  // namespace hivecal::streams
