#include "stream_pipeline.hpp"

#include <cstring>
#include <memory>
#include <sys/stat.h>

#include "hivecal/port/capture_file.hpp"
#include "text_util.hpp"

namespace hivecal::streams {
namespace {

constexpr int kReadTimeoutMs = 200;
constexpr std::uint64_t kProgressStepBytes = 256 * 1024;

/// Size of a file [bytes], 0 when unknown.
std::uint64_t file_bytes(const std::string& path) {
  struct stat info {};
  return ::stat(path.c_str(), &info) == 0 ? static_cast<std::uint64_t>(info.st_size) : 0;
}

/// The two logs of a run, read once before the passes (empty for a capture).
struct Logs {
  textio::RobotLog robot;      ///< when the robot input is a log
  textio::TrackerLog tracker;  ///< when the tracker input is a log
};

/// One input opened for one pass: a capture (bytes -> frames) or a log read before (records).
class Input {
 public:
  template <typename Log>
  bool open(const std::string& path, bool is_log, const Log& log, std::string* error) {
    if (is_log) {
      log_ = std::make_unique<LogRecordReader>(&log);
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
  const std::string& error() const { return log_ != nullptr ? no_error_ : bytes_->error(); }

 private:
  std::unique_ptr<port::CaptureFileSource> capture_;
  std::unique_ptr<SourceReader> bytes_;
  std::unique_ptr<FrameRecordReader> frames_;
  std::unique_ptr<LogRecordReader> log_;
  std::string no_error_;  ///< a log read whole has no read error left
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
            const Logs& logs, std::string* error) {
    return robot_input_.open(robot_path, kinds.robot_is_log, logs.robot, error) &&
           tracker_input_.open(tracker_path, kinds.tracker_is_log, logs.tracker, error);
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

Status LogRecordReader::next(StreamRecord* record) {
  record->kind = StreamRecord::Kind::end;
  if (joints_ != nullptr && next_ < joints_->size()) {
    record->kind = StreamRecord::Kind::joint_state;
    record->joint = (*joints_)[next_++];
    ++stats_.joint_states;
    ++stats_.frames_ok;
  } else if (points_ != nullptr && next_ < points_->size()) {
    record->kind = StreamRecord::Kind::tracker_point;
    record->point = (*points_)[next_++];
    ++stats_.tracker_points;
    ++stats_.frames_ok;
  }
  return Status::ok;
}

std::uint64_t LogRecordReader::bytes_read() const {
  const std::size_t size = joints_ != nullptr ? joints_->size() : points_->size();
  return size == 0 ? bytes_ : bytes_ / size * next_;
}

namespace {

/// Reads the inputs that are logs into *logs (kinds in *report); false with a message.
bool read_logs(const std::string& robot_path, const std::string& tracker_path, const textio::RobotLogOptions& options,
               Logs* logs, CaptureRunReport* report, std::string* error) {
  using textio::StreamFileKind;
  report->robot_is_log = textio::detect_stream_file(robot_path) != StreamFileKind::capture;
  report->tracker_is_log = textio::detect_stream_file(tracker_path) != StreamFileKind::capture;
  if (report->robot_is_log) {
    logs->robot = textio::read_robot_log(robot_path, options);
    report->robot_format = logs->robot.format;
    report->robot_log = logs->robot.counters;
    if (!logs->robot.ok) *error = logs->robot.error;
  }
  if (error->empty() && report->tracker_is_log) {
    logs->tracker = textio::read_tracker_log(tracker_path);
    report->tracker_format = logs->tracker.format;
    report->tracker_log = logs->tracker.counters;
    if (!logs->tracker.ok) *error = logs->tracker.error;
  }
  return error->empty();
}

/// A capture holding only the other stream's frames: the two files were swapped.
bool check_not_swapped(const std::string& robot_path, const std::string& tracker_path, const CaptureRunReport& report,
                       std::string* error) {
  const DecoderStats& r = report.decoding.robot_decoder;
  const DecoderStats& t = report.decoding.tracker_decoder;
  if (!report.robot_is_log && r.joint_states == 0 && r.tracker_points > 0) {
    *error = robot_path + ": contains tracker frames (" + std::to_string(r.tracker_points) +
             ") and no joint state: --robot and --tracker swapped?";
  } else if (!report.tracker_is_log && t.tracker_points == 0 && t.joint_states > 0) {
    *error = tracker_path + ": contains joint state frames (" + std::to_string(t.joint_states) +
             ") and no tracker point: --robot and --tracker swapped?";
  }
  return error->empty();
}

}  // namespace

bool extract_from_files(const std::string& robot_path, const std::string& tracker_path,
                        const ClockSyncConfig& clock_config, const ExtractionConfig& extraction_config,
                        DatasetBase* dataset, CaptureRunReport* report, std::string* error,
                        ExtractionObserver* observer, const PassProgress& progress,
                        const textio::RobotLogOptions& log_options) {
  const std::uint64_t total_bytes = file_bytes(robot_path) + file_bytes(tracker_path);
  // Each input's kind is read once here; both passes open it as that kind, a log's records
  // are read once and served to both.
  Logs logs;
  if (!read_logs(robot_path, tracker_path, log_options, &logs, report, error)) return false;
  // Large fixed-size objects: on the heap of the app, once (bounded whatever the input length).
  const auto estimator = std::make_unique<ClockEstimator<>>(clock_config);
  {
    Pass pass(1, progress, total_bytes);
    if (!pass.open(robot_path, tracker_path, *report, logs, error)) return false;
    report->clock_status = pass.finish(
        estimate_clock_from_streams(pass.robot(), pass.tracker(), estimator.get(), &report->clock, &report->decoding),
        error);
    report->clock_stats = estimator->stats();
    if (report->clock_status == Status::invalid_argument && !error->empty()) return false;
    if (!check_not_swapped(robot_path, tracker_path, *report, error)) return false;
    if (report->clock_status != Status::ok) return true;
  }
  const auto extractor = std::make_unique<SampleExtractor<>>(extraction_config, report->clock, dataset);
  extractor->set_observer(observer);
  Pass pass(2, progress, total_bytes);
  if (!pass.open(robot_path, tracker_path, *report, logs, error)) return false;
  report->extraction_status =
      pass.finish(extract_samples_from_streams(pass.robot(), pass.tracker(), extractor.get(), nullptr), error);
  report->counts = extractor->counts();
  return report->extraction_status != Status::invalid_argument || error->empty();
}

}  // namespace hivecal::streams
