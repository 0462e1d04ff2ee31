#include "streams/stream_pipeline.hpp"

#include <cstring>
#include <memory>
#include <sys/stat.h>

#include "textio/text_util.hpp"

namespace hivecal::streams {
namespace {

constexpr double kMaxLogTime_s = 1.8e13;  // microseconds still fit a u64 (and a double's integers)
constexpr std::uint64_t kProgressStepBytes = 256 * 1024;

/// One input opened for one pass: a capture (bytes -> frames) or a CSV log (rows).
class Input {
 public:
  port::Error open(const std::string& path, bool is_log, LogKind kind) {
    if (path == "-") return port::Error::input("'-': a stream is read twice (clock, then samples): give a file");
    if (is_log) {
      log_ = open_log_records(kind, path);
      return port::Error{};
    }
    capture_ = std::make_unique<port::InputFile>();
    const port::Error opened = capture_->open(path, port::kMaxStreamInputBytes);
    if (opened.ok()) frames_ = std::make_unique<FrameRecordReader>(capture_.get());
    return opened;
  }
  RecordReader& records() { return log_ != nullptr ? static_cast<RecordReader&>(*log_) : *frames_; }
  std::uint64_t bytes_read() const { return log_ != nullptr ? log_->bytes_read() : capture_->bytes_read(); }
  std::string error() const { return log_ != nullptr ? log_->error() : capture_->error().message; }
  std::uint64_t log_rows() const { return log_ != nullptr ? log_->rows() : 0; }

 private:
  std::unique_ptr<port::InputFile> capture_;
  std::unique_ptr<FrameRecordReader> frames_;
  std::unique_ptr<LogRecords> log_;
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
  port::Error open(const std::string& robot_path, const std::string& tracker_path, const CaptureRunReport& kinds) {
    port::Error error = robot_input_.open(robot_path, kinds.robot.is_log(), LogKind::robot);
    if (error.ok()) error = tracker_input_.open(tracker_path, kinds.tracker.is_log(), LogKind::tracker);
    return error;
  }
  const Input& robot_input() const { return robot_input_; }
  const Input& tracker_input() const { return tracker_input_; }
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

std::unique_ptr<LogRecords> open_log_records(LogKind kind, const std::string& path) {
  return std::make_unique<LogRecordReader>(kind, path);
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
  if (rows_ > 0 && *t_us <= last_us_) {
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
    const port::Error r = kind_ == Kind::robot ? robot_.open(path_) : tracker_.open(path_);
    if (!r.ok()) return fail(r.message);
  }
  bool got_row = false;
  port::Error r;
  if (kind_ == Kind::robot) {
    textio::RobotLogRow row;
    r = robot_.next(&row, &got_row);
    if (r.ok() && got_row) {
      if (!to_microseconds(row.t_s, &record->joint.timestamp_us)) return Status::read_failed;
      for (int j = 0; j < kJointCount; ++j) record->joint.q_rad[j] = row.q_rad(j);
      record->kind = StreamRecord::Kind::joint_state;
    }
  } else {
    textio::TrackerLogRow row;
    r = tracker_.next(&row, &got_row);
    if (r.ok() && got_row) {
      if (!to_microseconds(row.t_s, &record->point.timestamp_us)) return Status::read_failed;
      for (int k = 0; k < 3; ++k) record->point.point_m[k] = row.point_m(k);
      record->point.status = row.status;
      record->kind = StreamRecord::Kind::tracker_point;
    }
  }
  if (!r.ok()) return fail(r.message);
  if (got_row) ++rows_;
  return Status::ok;
}

namespace {

/// Size of an input [bytes], 0 when unknown (for progress only).
std::uint64_t size_of(const std::string& path) {
  port::InputFile file;
  return file.open(path, port::kMaxStreamInputBytes).ok() ? file.size_bytes() : 0;
}

/// The counts of one input after the first pass.
void count_input(const Input& input, const DecoderStats& frames, bool robot, StreamInputCounts* counts) {
  counts->frames = counts->is_log() ? DecoderStats{} : frames;
  counts->log_rows = input.log_rows();
  counts->records = counts->is_log() ? input.log_rows() : (robot ? frames.joint_states : frames.tracker_points);
}

}  // namespace

port::Error extract_from_files(const std::string& robot_path, const std::string& tracker_path,
                               const ClockSyncConfig& clock_config, const ExtractionConfig& extraction_config,
                               DatasetBase* dataset, CaptureRunReport* report, ExtractionObserver* observer,
                               const PassProgress& progress) {
  // Each input's kind is read once here; both passes open it as that kind.
  report->robot.kind = textio::detect_stream_file(robot_path);
  report->tracker.kind = textio::detect_stream_file(tracker_path);
  // Large fixed-size objects: on the heap of the app, once (bounded whatever the input length).
  const auto estimator = std::make_unique<ClockEstimator<>>(clock_config);
  const std::uint64_t total_bytes = size_of(robot_path) + size_of(tracker_path);
  std::string error;
  {
    Pass pass(1, progress, total_bytes);
    port::Error opened = pass.open(robot_path, tracker_path, *report);
    if (!opened.ok()) return opened;
    PassStats decoding;
    report->clock_status = pass.finish(
        estimate_clock_from_streams(pass.robot(), pass.tracker(), estimator.get(), &report->clock, &decoding), &error);
    count_input(pass.robot_input(), decoding.robot_decoder, true, &report->robot);
    count_input(pass.tracker_input(), decoding.tracker_decoder, false, &report->tracker);
    report->clock_stats = estimator->stats();
    if (report->clock_status == Status::invalid_argument && !error.empty()) return port::Error::input(error);
    if (report->clock_status != Status::ok) return port::Error{};
  }
  const auto extractor = std::make_unique<SampleExtractor<>>(extraction_config, report->clock, dataset);
  extractor->set_observer(observer);
  Pass pass(2, progress, total_bytes);
  port::Error opened = pass.open(robot_path, tracker_path, *report);
  if (!opened.ok()) return opened;
  report->extraction_status =
      pass.finish(extract_samples_from_streams(pass.robot(), pass.tracker(), extractor.get(), nullptr), &error);
  report->counts = extractor->counts();
  if (report->extraction_status == Status::invalid_argument && !error.empty()) return port::Error::input(error);
  return port::Error{};
}

}  // namespace hivecal::streams
