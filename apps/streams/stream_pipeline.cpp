#include "stream_pipeline.hpp"

#include <cstring>
#include <memory>
#include <sys/stat.h>

#include "hivecal/port/capture_file.hpp"
#include "text_util.hpp"

namespace hivecal::streams {
namespace {

constexpr int kReadTimeoutMs = 200;
constexpr double kMaxLogTime_s = 1.8e13;  // microseconds still fit a u64 (and a double's integers)
constexpr std::uint64_t kProgressStepBytes = 256 * 1024;

/// Size of a file [bytes], 0 when unknown.
std::uint64_t file_bytes(const std::string& path) {
  struct stat info {};
  return ::stat(path.c_str(), &info) == 0 ? static_cast<std::uint64_t>(info.st_size) : 0;
}

/// One input opened for one pass: a capture (bytes -> frames) or a CSV log (rows).
class Input {
 public:
  bool open(const std::string& path, bool is_log, LogRecordReader::Kind kind, std::string* error) {
    if (is_log) {
      log_ = std::make_unique<LogRecordReader>(kind, path);
      return true;
    }
    capture_ = std::make_unique<port::CaptureFileSource>(path);
    if (!capture_->open(error)) return false;
    bytes_ = std::make_unique<SourceReader>(capture_.get());
    frames_ = std::make_unique<FrameRecordReader>(bytes_.get());
    return true;
  }
  RecordReader& records() { return log_ != nullptr ? static_cast<RecordReader&>(*log_) : *frames_; }
  std::uint64_t bytes_read() const { return log_ != nullptr ? log_->bytes_read() : bytes_->bytes_read(); }
  const std::string& error() const { return log_ != nullptr ? log_->error() : bytes_->error(); }

 private:
  std::unique_ptr<port::CaptureFileSource> capture_;
  std::unique_ptr<SourceReader> bytes_;
  std::unique_ptr<FrameRecordReader> frames_;
  std::unique_ptr<LogRecordReader> log_;
};

/// A RecordReader that reports progress as its input is read (the passes live in lib/).
class ProgressReader final : public RecordReader {
 public:
  ProgressReader(Input* input, const std::function<void()>& tick) : input_(input), tick_(tick) {}
  Status next(StreamRecord* record) override {
    tick_();
    return input_->records().next(record);
  }
  const DecoderStats& counters() const override { return input_->records().counters(); }

 private:
  Input* input_;
  const std::function<void()>& tick_;
};

/// The two inputs of one pass, with progress.
class Pass {
 public:
  Pass(int number, const PassProgress& progress, std::uint64_t total_bytes)
      : number_(number), progress_(progress), total_(total_bytes), tick_([this] { tick(); }),
        robot_(&robot_input_, tick_), tracker_(&tracker_input_, tick_) {}
  bool open(const std::string& robot_path, const std::string& tracker_path, const CaptureRunReport& kinds,
            std::string* error) {
    return robot_input_.open(robot_path, kinds.robot_is_log, LogRecordReader::Kind::robot, error) &&
           tracker_input_.open(tracker_path, kinds.tracker_is_log, LogRecordReader::Kind::tracker, error);
  }
  RecordReader& robot() { return robot_; }
  RecordReader& tracker() { return tracker_; }
  /// read_failed becomes invalid_argument with the reader's message.
  Status finish(Status status, std::string* error) {
    if (progress_) progress_(number_, bytes_done(), total_);
    if (status != Status::read_failed) return status;
    *error = robot_input_.error().empty() ? tracker_input_.error() : robot_input_.error();
    return Status::invalid_argument;
  }

 private:
  std::uint64_t bytes_done() const { return robot_input_.bytes_read() + tracker_input_.bytes_read(); }
  void tick() {
    if (!progress_ || ++calls_ % 64 != 0) return;
    const std::uint64_t done = bytes_done();
    if (done < next_report_) return;
    next_report_ = done + kProgressStepBytes;
    progress_(number_, done, total_);
  }

  int number_;
  const PassProgress& progress_;
  std::uint64_t total_;
  std::uint64_t calls_ = 0;
  std::uint64_t next_report_ = 0;
  std::function<void()> tick_;
  Input robot_input_;
  Input tracker_input_;
  ProgressReader robot_;
  ProgressReader tracker_;
};

}  // namespace

Status SourceReader::read(std::uint8_t* out, std::size_t capacity, std::size_t* count) {
  for (;;) {
    const port::ReadResult got = source_->read(out, capacity, kReadTimeoutMs);
    if (got.status == port::ReadStatus::data) {
      *count = got.bytes;
      bytes_ += got.bytes;
      return Status::ok;
    }
    if (got.status == port::ReadStatus::end_of_stream) {
      *count = 0;
      return Status::ok;
    }
    if (got.status == port::ReadStatus::error) {
      error_ = source_->name() + ": read failed: " + std::strerror(got.error_number);
      return Status::read_failed;
    }
  }
}

Status LogRecordReader::fail(const std::string& problem) {
  error_ = problem;
  return Status::read_failed;
}

bool LogRecordReader::to_microseconds(double t_s, std::uint64_t* t_us) {
  if (!(t_s >= 0.0 && t_s <= kMaxLogTime_s)) {
    error_ = path_ + ": timestamp " + textio::format_double(t_s) + " s outside 0 .. 1.8e13 s";
    return false;
  }
  *t_us = static_cast<std::uint64_t>(t_s * 1e6 + 0.5);
  if (stats_.frames_ok > 0 && *t_us <= last_us_) {
    error_ = path_ + ": timestamps " + textio::format_double(t_s) + " s and the previous one are less than 1 us apart";
    return false;
  }
  last_us_ = *t_us;
  return true;
}

Status LogRecordReader::next(StreamRecord* record) {
  record->kind = StreamRecord::Kind::end;
  if (!error_.empty()) return Status::read_failed;
  if (!opened_) {
    opened_ = true;
    const textio::ParseResult r = kind_ == Kind::robot ? robot_.open(path_) : tracker_.open(path_);
    if (!r.ok) return fail(r.message);
  }
  bool got_row = false;
  textio::ParseResult r;
  if (kind_ == Kind::robot) {
    textio::RobotLogRow row;
    r = robot_.next(&row, &got_row);
    if (r.ok && got_row) {
      if (!to_microseconds(row.t_s, &record->joint.timestamp_us)) return Status::read_failed;
      for (int j = 0; j < kJointCount; ++j) record->joint.q_rad[j] = row.q_rad(j);
      record->kind = StreamRecord::Kind::joint_state;
      ++stats_.joint_states;
    }
  } else {
    textio::TrackerLogRow row;
    r = tracker_.next(&row, &got_row);
    if (r.ok && got_row) {
      if (!to_microseconds(row.t_s, &record->point.timestamp_us)) return Status::read_failed;
      for (int k = 0; k < 3; ++k) record->point.point_m[k] = row.point_m(k);
      record->point.status = row.status;
      record->kind = StreamRecord::Kind::tracker_point;
      ++stats_.tracker_points;
    }
  }
  if (!r.ok) return fail(r.message);
  if (got_row) ++stats_.frames_ok;
  return Status::ok;
}

bool extract_from_files(const std::string& robot_path, const std::string& tracker_path,
                        const ClockSyncConfig& clock_config, const ExtractionConfig& extraction_config,
                        DatasetBase* dataset, CaptureRunReport* report, std::string* error,
                        ExtractionObserver* observer, const PassProgress& progress) {
  const std::uint64_t total_bytes = file_bytes(robot_path) + file_bytes(tracker_path);
  // Each input's kind is read once here; both passes open it as that kind.
  report->robot_is_log = textio::detect_stream_file(robot_path) == textio::StreamFileKind::csv_log;
  report->tracker_is_log = textio::detect_stream_file(tracker_path) == textio::StreamFileKind::csv_log;
  // Large fixed-size objects: on the heap of the app, once (bounded whatever the input length).
  const auto estimator = std::make_unique<ClockEstimator<>>(clock_config);
  {
    Pass pass(1, progress, total_bytes);
    if (!pass.open(robot_path, tracker_path, *report, error)) return false;
    report->clock_status = pass.finish(
        estimate_clock_from_streams(pass.robot(), pass.tracker(), estimator.get(), &report->clock, &report->decoding),
        error);
    report->clock_stats = estimator->stats();
    if (report->clock_status == Status::invalid_argument && !error->empty()) return false;
    if (report->clock_status != Status::ok) return true;
  }
  const auto extractor = std::make_unique<SampleExtractor<>>(extraction_config, report->clock, dataset);
  extractor->set_observer(observer);
  Pass pass(2, progress, total_bytes);
  if (!pass.open(robot_path, tracker_path, *report, error)) return false;
  report->extraction_status =
      pass.finish(extract_samples_from_streams(pass.robot(), pass.tracker(), extractor.get(), nullptr), error);
  report->counts = extractor->counts();
  return report->extraction_status != Status::invalid_argument || error->empty();
}

}  // namespace hivecal::streams
