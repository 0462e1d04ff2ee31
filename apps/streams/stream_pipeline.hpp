// Wires port/ to lib/ for the stream path: byte sources (capture files, serial ports) ->
// StreamDecoder, or CSV logs -> rows, then ClockEstimator (pass 1) -> SampleExtractor
// (pass 2) -> dataset. Memory stays bounded: records are read one chunk at a time.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <string>

#include "hivecal/clock_sync.hpp"
#include "hivecal/codec.hpp"
#include "hivecal/port/byte_source.hpp"
#include "hivecal/sample_extraction.hpp"
#include "csv.hpp"

namespace hivecal::streams {

/// Short queues of records read from one stream, refilled on demand: the pipeline's view of
/// a capture (decoded frames) or of a CSV log (parsed rows) alike.
class RecordSource {
 public:
  virtual ~RecordSource() = default;
  /// Reads until a record is queued or the input ends; false at the end with nothing queued
  /// (or on a read or parse error: see error()).
  virtual bool fill() = 0;
  /// Records read so far, per type (a CSV log counts its rows as records).
  virtual const DecoderStats& decoder_stats() const = 0;
  /// Bytes of the input consumed so far [bytes] (for progress).
  virtual std::uint64_t bytes_read() const = 0;
  std::deque<JointStateRecord>& joints() { return joints_; }      ///< queued robot records
  std::deque<TrackerPointRecord>& points() { return points_; }    ///< queued tracker records
  const std::string& error() const { return error_; }            ///< read or parse error, if any

 protected:
  std::deque<JointStateRecord> joints_;
  std::deque<TrackerPointRecord> points_;
  std::string error_;
};

/// Decodes a byte source into the queues, one read chunk at a time.
class RecordQueue final : public RecordSource, public FrameHandler {
 public:
  /// A queue over `source` (not owned; nullptr when fed with feed() only).
  explicit RecordQueue(port::ByteSource* source) : source_(source) {}
  bool fill() override;
  const DecoderStats& decoder_stats() const override { return decoder_.stats(); }
  /// Decodes bytes obtained elsewhere (e.g. a recorder's tap) into the queues.
  void feed(const std::uint8_t* bytes, std::size_t count) { decoder_.feed(bytes, count, *this); }
  std::uint64_t bytes_read() const override { return decoder_.stats().bytes_total; }

  void on_joint_state(const JointStateRecord& record) override { joints_.push_back(record); }
  void on_tracker_point(const TrackerPointRecord& record) override { points_.push_back(record); }

 private:
  port::ByteSource* source_;
  StreamDecoder decoder_;
  bool ended_ = false;
};

/// Parses a CSV log of io-formats.md (robot `t,q1..q6` or tracker `t,x,y,z[,status]`) into the
/// queues, a few rows at a time. Seconds become microseconds of the record timestamps; a log
/// has no sequence numbers, velocities or currents (they stay 0, nothing downstream uses them).
class LogRecordQueue final : public RecordSource {
 public:
  /// Which log the file holds.
  enum class Kind { robot, tracker };
  /// A queue over the log at `path`, opened by the first fill().
  LogRecordQueue(Kind kind, std::string path) : kind_(kind), path_(std::move(path)) {}
  bool fill() override;
  const DecoderStats& decoder_stats() const override { return stats_; }
  std::uint64_t bytes_read() const override {
    return kind_ == Kind::robot ? robot_.bytes_read() : tracker_.bytes_read();
  }

 private:
  bool open();
  bool read_row();
  bool to_microseconds(double t_s, std::uint64_t* t_us);

  Kind kind_;
  std::string path_;
  bool opened_ = false;
  bool ended_ = false;
  textio::RobotLogReader robot_;
  textio::TrackerLogReader tracker_;
  DecoderStats stats_;
  std::uint64_t last_us_ = 0;
};

/// Opens `path` as a record source of the given stream: a CSV log or a capture, by content.
/// `bytes` receives the capture's byte source (kept alive by the caller); false with *error
/// when a capture cannot be opened.
std::unique_ptr<RecordSource> open_record_source(const std::string& path, LogRecordQueue::Kind stream,
                                                 std::unique_ptr<port::ByteSource>* bytes, std::string* error);

/// Told how far a pass over the two inputs is: pass 1 (clock) or 2 (samples), bytes read of
/// both inputs so far and in all (0 when unknown) [bytes]. Called about every 256 kB read, and
/// once at the end of each pass.
using PassProgress = std::function<void(int pass, std::uint64_t bytes_done, std::uint64_t bytes_total)>;

/// Counters of one pass over the two streams.
struct PassStats {
  DecoderStats robot_decoder;     ///< frames of the robot stream
  DecoderStats tracker_decoder;   ///< frames of the tracker stream
};

/// Pass 1: every record of both sources into `estimator`, then estimate() into *fit.
/// Returns the estimate's status; I/O problems give invalid_argument with *error set.
Status estimate_clock(RecordSource* robot, RecordSource* tracker, ClockEstimatorBase* estimator,
                      ClockFit* fit, PassStats* stats, std::string* error, const PassProgress& progress = {});

/// Pass 2: both sources merged in robot-clock order (through extractor->clock()) into
/// `extractor`, then finish(). Returns ok, dataset_full, or invalid_argument with *error set.
Status extract_samples(RecordSource* robot, RecordSource* tracker, SampleExtractorBase* extractor,
                       PassStats* stats, std::string* error, const PassProgress& progress = {});

/// Everything a two-pass run over capture files reports.
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
