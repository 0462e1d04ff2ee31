// Wires port/ and the text formats to lib/ for the stream path: each input is a serial
// capture (port::InputFile, a lib ByteReader -> FrameRecordReader) or a text log
// (open_log_records -> LogRecordReader), then
// the library's two passes (hivecal/capture_pipeline.hpp: ClockEstimator, then
// SampleExtractor in robot-clock order) -> dataset. Memory stays bounded: records are read
// a chunk or a row at a time.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <string>

#include "hivecal/port/error.hpp"
#include "hivecal/port/input_file.hpp"
#include "hivecal/sync/capture_pipeline.hpp"
#include "hivecal/sync/clock_sync.hpp"
#include "hivecal/sync/sample_extraction.hpp"
#include "hivecal/wire/codec.hpp"
#include "textio/csv.hpp"

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

/// Which stream a log holds.
enum class LogKind { robot, tracker };

/// Records of a text log, whatever tool wrote it: what the two passes need of any log reader.
/// A log counts rows, not frames: counters() (the library's frame counters) stays zero and
/// rows() says how many records the log gave.
class LogRecords : public RecordReader {
 public:
  virtual ~LogRecords() = default;
  virtual std::uint64_t rows() const = 0;         ///< data rows turned into records
  virtual const std::string& error() const = 0;   ///< what failed (file:line: what), if anything
  virtual std::uint64_t bytes_read() const = 0;   ///< [bytes]

 protected:
  LogRecords() = default;
  LogRecords(const LogRecords&) = default;
  LogRecords& operator=(const LogRecords&) = default;
};

/// Records of a CSV log of io-formats.md (robot `t,q1..q6` or tracker `t,x,y,z[,status]`),
/// one row per record. Seconds become whole microseconds; a log has no sequence numbers,
/// velocities or currents (they stay 0, nothing downstream uses them).
class LogRecordReader final : public LogRecords {
 public:
  using Kind = LogKind;  ///< which log the file holds
  /// A reader of the log at `path`, opened by the first next().
  LogRecordReader(Kind kind, std::string path) : kind_(kind), path_(std::move(path)) {}
  Status next(StreamRecord* record) override;
  const DecoderStats& counters() const override { return no_frames_; }
  std::uint64_t rows() const override { return rows_; }
  const std::string& error() const override { return error_; }
  std::uint64_t bytes_read() const override {
    return kind_ == Kind::robot ? robot_.bytes_read() : tracker_.bytes_read();
  }

 private:
  Status fail(const std::string& problem);
  bool to_microseconds(double t_s, std::uint64_t* t_us);

  Kind kind_;
  std::string path_;
  bool opened_ = false;
  textio::RobotLogReader robot_;
  textio::TrackerLogReader tracker_;
  DecoderStats no_frames_;
  std::uint64_t rows_ = 0;
  std::uint64_t last_us_ = 0;
  std::string error_;
};

/// The one place a log file becomes records: today the CSV logs of io-formats.md; the readers
/// of other tools' logs (apps/textio/logs*) plug in here, chosen by content.
std::unique_ptr<LogRecords> open_log_records(LogKind kind, const std::string& path);

/// Told how far a pass over the two inputs is: pass 1 (clock) or 2 (samples), bytes read of
/// both inputs so far and in all (0 when unknown) [bytes]. Called about every 256 kB read, and
/// once at the end of each pass.
using PassProgress = std::function<void(int pass, std::uint64_t bytes_done, std::uint64_t bytes_total)>;

/// Counters of one pass over the two streams.
using PassStats = StreamPassStats;

/// What one input of a two-pass run held.
struct StreamInputCounts {
  textio::StreamFileKind kind = textio::StreamFileKind::capture;  ///< capture or CSV log (by content)
  DecoderStats frames;         ///< a capture's frame counters (first pass); zero for a log
  std::uint64_t log_rows = 0;  ///< a log's data rows (first pass); zero for a capture
  std::uint64_t records = 0;   ///< joint states (robot input) or tracker points (tracker input)
  bool is_log() const { return kind == textio::StreamFileKind::csv_log; }  ///< a text log
};

/// Everything a two-pass run over two files reports.
struct CaptureRunReport {
  Status clock_status = Status::ok;       ///< outcome of the clock estimation
  ClockFit clock;                          ///< the clock relation (when clock_status is ok)
  ClockProfileStats clock_stats;           ///< what went into the clock profiles
  StreamInputCounts robot;                 ///< what the robot input held
  StreamInputCounts tracker;               ///< what the tracker input held
  Status extraction_status = Status::ok;  ///< ok or dataset_full
  ExtractionCounts counts;                 ///< kept / dropped per reason
};

/// Both passes over two files into `dataset`; each is a serial capture or a CSV log
/// (detected by content, so the two may differ). Fault::input when a file cannot be read or
/// parsed; a failed clock fit is reported in *report (no extraction then).
port::Error extract_from_files(const std::string& robot_path, const std::string& tracker_path,
                        const ClockSyncConfig& clock_config, const ExtractionConfig& extraction_config,
                        DatasetBase* dataset, CaptureRunReport* report,
                        ExtractionObserver* observer = nullptr, const PassProgress& progress = {});

}  // namespace hivecal::streams
