// Wires port/ and the text formats to lib/ for the stream path: each input is a serial
// capture (port::InputFile, a lib ByteReader -> FrameRecordReader) or a text log
// or ROS 2 bag of any tool (open_log_records -> LogRecordReader, read once), then
// the library's capture front (hivecal/sync/capture_dataset.hpp: its two passes, ClockEstimator,
// then SampleExtractor in robot-clock order) -> dataset; this file only supplies the readers. A capture's memory stays
// bounded (read a chunk at a time); a log's records are held (~136 B a robot row: 41 MB for 10 min at 500 Hz).
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "hivecal/port/error.hpp"
#include "hivecal/port/input_file.hpp"
#include "hivecal/sync/capture_dataset.hpp"
#include "hivecal/sync/capture_pipeline.hpp"
#include "hivecal/sync/clock_sync.hpp"
#include "hivecal/sync/sample_extraction.hpp"
#include "hivecal/wire/codec.hpp"
#include "textio/logs.hpp"

namespace hivecal::streams {

/// Decodes bytes obtained elsewhere (e.g. a recorder's tap) into queues of records.
class RecordQueue final : public FrameHandler {
 public:
  std::deque<JointStateRecord>& joints() { return joints_; }              ///< decoded robot records
  std::deque<TrackerPointRecord>& points() { return points_; }            ///< decoded tracker records
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

/// Which stream a log holds.
enum class LogKind { robot, tracker };

/// Records of a text log, whatever tool wrote it: what the two passes need of any log reader.
/// A log counts rows, not frames: counters() (the library's frame counters) stays zero and
/// rows() says how many records the log gave.
class LogRecords : public RecordReader {
 public:
  virtual ~LogRecords() = default;
  virtual std::uint64_t rows() const = 0;        ///< data rows turned into records
  virtual const std::string& error() const = 0;  ///< what failed (file:line: what), if anything
  virtual std::uint64_t bytes_read() const = 0;  ///< [bytes]

 protected:
  LogRecords() = default;
  LogRecords(const LogRecords&) = default;
  LogRecords& operator=(const LogRecords&) = default;
};

/// Records of a log read whole by textio (textio/logs.hpp: hivecal CSV, UR RTDE, rostopic,
/// ROS 2 bag, tracker exports), served in order. A log has no sequence numbers, velocities
/// or currents (they stay 0, nothing downstream uses them). A log that could not be read
/// gives read_failed at the first next(), with error() naming file:line.
class LogRecordReader final : public LogRecords {
 public:
  /// Serves `log`'s records (shared: passes replay the same log).
  explicit LogRecordReader(std::shared_ptr<const textio::RobotLog> log);
  /// Serves `log`'s records (shared: passes replay the same log).
  explicit LogRecordReader(std::shared_ptr<const textio::TrackerLog> log);
  Status next(StreamRecord* record) override;
  const DecoderStats& counters() const override { return no_frames_; }
  std::uint64_t rows() const override { return next_; }
  const std::string& error() const override { return error_; }
  /// The log's bytes in proportion to the records served so far [bytes].
  std::uint64_t bytes_read() const override;
  /// A reader of the same log from its start (no second read of the file).
  std::unique_ptr<LogRecordReader> replay() const;
  textio::LogFormat format() const { return format_; }                       ///< what the log is
  const textio::LogCounters& log_counters() const { return log_counters_; }  ///< the log's rows per reason

 private:
  std::shared_ptr<const textio::RobotLog> joints_;
  std::shared_ptr<const textio::TrackerLog> points_;
  std::size_t size_ = 0;
  std::uint64_t bytes_ = 0;
  std::size_t next_ = 0;
  textio::LogFormat format_ = textio::LogFormat::unknown;
  textio::LogCounters log_counters_;
  DecoderStats no_frames_;
  std::string error_;
};

/// The one place a log file becomes records: any tool's log (textio::read_robot_log /
/// read_tracker_log, chosen by content), read once, whole. `options.units` apply to the
/// columns without a bracket unit of either kind of log.
std::unique_ptr<LogRecordReader> open_log_records(LogKind kind, const std::string& path,
                                                  const textio::RobotLogOptions& options = {});

/// Told how far a pass over the two inputs is: pass 1 (clock) or 2 (samples), bytes read of
/// both inputs so far and in all (0 when unknown) [bytes]. Called about every 256 kB read, and
/// once at the end of each pass.
using PassProgress = std::function<void(int pass, std::uint64_t bytes_done, std::uint64_t bytes_total)>;

/// Counters of one pass over the two streams.
using PassStats = StreamPassStats;

/// What one input of a two-pass run held.
struct StreamInputCounts {
  textio::StreamFileKind kind = textio::StreamFileKind::capture;  ///< capture or log (by content)
  textio::LogFormat format = textio::LogFormat::unknown;          ///< a log's format
  textio::LogCounters log;                                        ///< a log's rows, dropped per reason
  DecoderStats frames;         ///< a capture's frame counters (first pass); zero for a log
  std::uint64_t log_rows = 0;  ///< a log's data rows (first pass); zero for a capture
  std::uint64_t records = 0;   ///< joint states (robot input) or tracker points (tracker input)
  bool is_log() const { return kind != textio::StreamFileKind::capture; }  ///< a log (text or bag)
};

/// Everything a two-pass run over two files reports.
struct CaptureRunReport {
  Status clock_status = Status::ok;  ///< outcome of the clock estimation
  ClockFit clock;                    ///< the clock relation (when clock_status is ok)
  ClockProfileStats clock_stats;     ///< what went into the clock profiles
  std::vector<ClockMatchBin>
      clock_match;            ///< the profiles the clock fit matched, <= kClockMatchBins time bins (clock ok)
  StreamInputCounts robot;    ///< what the robot input held
  StreamInputCounts tracker;  ///< what the tracker input held
  Status extraction_status = Status::ok;  ///< ok or dataset_full
  ExtractionCounts counts;                ///< kept / dropped per reason
};

/// Both passes over two files into `dataset`; each is a serial capture or a log (detected by
/// content, so the two may differ; a log is read once, whole, and replayed to both passes).
/// Fault::input when a file cannot be read or parsed, or when a capture holds only the other
/// stream's frames (swapped inputs); a failed clock fit is reported in *report (no
/// extraction then). `log_options`: how to read the logs (joint names of ROS logs, units of
/// columns without a bracket unit).
port::Error extract_from_files(const std::string& robot_path, const std::string& tracker_path,
                               const ClockSyncConfig& clock_config, const ExtractionConfig& extraction_config,
                               DatasetBase* dataset, CaptureRunReport* report, ExtractionObserver* observer = nullptr,
                               const PassProgress& progress = {}, const textio::RobotLogOptions& log_options = {});

}  // namespace hivecal::streams
