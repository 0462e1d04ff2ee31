#include "streams/stream_pipeline.hpp"

#include <cstring>
#include <memory>
#include <sys/stat.h>

#include "textio/text_util.hpp"

namespace hivecal::streams {
namespace {

constexpr std::uint64_t kProgressStepBytes = 256 * 1024;

/// One input opened for one pass: a capture (bytes -> frames) or a CSV log (rows).
class Input {
 public:
  /// `loaded`: the log read before the passes, when the input is one.
  port::Error open(const std::string& path, const LogRecordReader* loaded) {
    if (path == "-") return port::Error::input("'-': a stream is read twice (clock, then samples): give a file");
    if (loaded != nullptr) {
      log_ = loaded->replay();
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
      : number_(number),
        progress_(progress),
        total_(total_bytes),
        tick_([this] { tick(); }),
        robot_(&robot_input_, tick_),
        tracker_(&tracker_input_, tick_) {}
  port::Error open(const std::string& robot_path, const std::string& tracker_path, const LogRecordReader* robot_log,
                   const LogRecordReader* tracker_log) {
    port::Error error = robot_input_.open(robot_path, robot_log);
    if (error.ok()) error = tracker_input_.open(tracker_path, tracker_log);
    return error;
  }
  const Input& robot_input() const { return robot_input_; }
  const Input& tracker_input() const { return tracker_input_; }
  RecordReader& robot() { return robot_; }
  RecordReader& tracker() { return tracker_; }
  /// The pass's last progress line (once).
  void end() {
    if (progress_ && !ended_) progress_(number_, bytes_done(), total_);
    ended_ = true;
  }
  /// Ends the pass; read_failed becomes invalid_argument with the reader's message.
  Status finish(Status status, std::string* error) {
    end();
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
  bool ended_ = false;
  std::function<void()> tick_;
  Input robot_input_;
  Input tracker_input_;
  ProgressReader robot_;
  ProgressReader tracker_;
};

}  // namespace

LogRecordReader::LogRecordReader(std::shared_ptr<const textio::RobotLog> log)
    : joints_(std::move(log)),
      size_(joints_->records.size()),
      bytes_(joints_->bytes_read),
      format_(joints_->format),
      log_counters_(joints_->counters),
      error_(joints_->ok ? "" : joints_->error) {}

LogRecordReader::LogRecordReader(std::shared_ptr<const textio::TrackerLog> log)
    : points_(std::move(log)),
      size_(points_->records.size()),
      bytes_(points_->bytes_read),
      format_(points_->format),
      log_counters_(points_->counters),
      error_(points_->ok ? "" : points_->error) {}

Status LogRecordReader::next(StreamRecord* record) {
  record->kind = StreamRecord::Kind::end;
  if (!error_.empty()) return Status::read_failed;
  if (next_ == size_) return Status::ok;
  if (joints_ != nullptr) {
    record->kind = StreamRecord::Kind::joint_state;
    record->joint = joints_->records[next_++];
  } else {
    record->kind = StreamRecord::Kind::tracker_point;
    record->point = points_->records[next_++];
  }
  return Status::ok;
}

std::uint64_t LogRecordReader::bytes_read() const {
  return size_ == 0 ? bytes_ : bytes_ / size_ * next_;
}

std::unique_ptr<LogRecordReader> LogRecordReader::replay() const {
  return joints_ != nullptr ? std::make_unique<LogRecordReader>(joints_) : std::make_unique<LogRecordReader>(points_);
}

std::unique_ptr<LogRecordReader> open_log_records(LogKind kind, const std::string& path,
                                                  const textio::RobotLogOptions& options) {
  if (kind == LogKind::robot) {
    return std::make_unique<LogRecordReader>(
        std::make_shared<const textio::RobotLog>(textio::read_robot_log(path, options)));
  }
  return std::make_unique<LogRecordReader>(
      std::make_shared<const textio::TrackerLog>(textio::read_tracker_log(path, options.units)));
}

namespace {

/// Size of an input [bytes], 0 when unknown (for progress only).
std::uint64_t size_of(const std::string& path) {
  port::InputFile file;
  return file.open(path, port::kMaxStreamInputBytes).ok() ? file.size_bytes() : 0;
}

/// The counts of one input after the first pass.
void count_input(const Input& input, const DecoderStats& frames, bool robot, const LogRecordReader* log,
                 StreamInputCounts* counts) {
  counts->frames = counts->is_log() ? DecoderStats{} : frames;
  if (log != nullptr) {
    counts->format = log->format();
    counts->log = log->log_counters();
  }
  counts->log_rows = input.log_rows();
  counts->records = counts->is_log() ? input.log_rows() : (robot ? frames.joint_states : frames.tracker_points);
}

/// A capture holding only the other stream's frames: the two files were swapped.
port::Error check_not_swapped(const std::string& robot_path, const std::string& tracker_path,
                              const CaptureRunReport& report) {
  const DecoderStats& r = report.robot.frames;
  const DecoderStats& t = report.tracker.frames;
  if (!report.robot.is_log() && r.joint_states == 0 && r.tracker_points > 0) {
    return port::Error::input(robot_path + ": contains tracker frames (" + std::to_string(r.tracker_points) +
                              ") and no joint state: --robot and --tracker swapped?");
  }
  if (!report.tracker.is_log() && t.tracker_points == 0 && t.joint_states > 0) {
    return port::Error::input(tracker_path + ": contains joint state frames (" + std::to_string(t.joint_states) +
                              ") and no tracker point: --robot and --tracker swapped?");
  }
  return port::Error{};
}

/// The two files as lib's RecordSource: each open() is the next pass (1: clock, 2: samples),
/// whose readers report progress; both passes' inputs stay for the counts and the messages.
class FileRecordSource final : public RecordSource {
 public:
  FileRecordSource(const std::string& robot_path, const std::string& tracker_path, const LogRecordReader* robot_log,
                   const LogRecordReader* tracker_log, const PassProgress& progress, std::uint64_t total_bytes)
      : robot_path_(robot_path),
        tracker_path_(tracker_path),
        robot_log_(robot_log),
        tracker_log_(tracker_log),
        progress_(progress),
        total_(total_bytes) {}
  Status open(RecordReader** robot, RecordReader** tracker) override {
    if (opened_ == 2) return Status::read_failed;
    if (opened_ == 1) passes_[0]->end();  // pass 1 is over: its last progress line before pass 2's
    std::unique_ptr<Pass>& pass = passes_[opened_];
    pass = std::make_unique<Pass>(opened_ + 1, progress_, total_);
    ++opened_;
    open_error_ = pass->open(robot_path_, tracker_path_, robot_log_, tracker_log_);
    if (!open_error_.ok()) return Status::read_failed;
    *robot = &pass->robot();
    *tracker = &pass->tracker();
    return Status::ok;
  }
  int opened() const { return opened_; }                         ///< passes opened [-]
  Pass& pass(int number) { return *passes_[number - 1]; }        ///< pass 1 or 2 (opened)
  const port::Error& open_error() const { return open_error_; }  ///< why the last open failed

 private:
  std::string robot_path_;
  std::string tracker_path_;
  const LogRecordReader* robot_log_;
  const LogRecordReader* tracker_log_;
  const PassProgress& progress_;
  std::uint64_t total_;
  int opened_ = 0;
  std::unique_ptr<Pass> passes_[2];
  port::Error open_error_;
};

/// What the clock fit matched, for the report (observation only; a failure leaves it empty).
class ClockMatchRecorder final : public ClockPassObserver {
 public:
  void on_clock_pass(const ClockEstimatorBase& estimator, Status status, const ClockFit& fit) override {
    const auto match = std::make_unique<ClockMatch>();  // ~25 kB: not on the stack
    if (status != Status::ok || estimator.match_profiles(fit, kClockMatchBins, match.get()) != Status::ok) return;
    bins.assign(match->bins, match->bins + match->count);
  }
  std::vector<ClockMatchBin> bins;  ///< time bins, in order
};

/// The front's workspace at the host's capacities (ClockEstimator<>, SampleExtractor<>).
using HostCaptureWorkspace = CaptureWorkspace<kDefaultClockRobotKnots, kDefaultClockTrackerPoints, 1024, 64>;

}  // namespace

port::Error extract_from_files(const std::string& robot_path, const std::string& tracker_path,
                               const ClockSyncConfig& clock_config, const ExtractionConfig& extraction_config,
                               DatasetBase* dataset, CaptureRunReport* report, ExtractionObserver* observer,
                               const PassProgress& progress, const textio::RobotLogOptions& log_options) {
  // Each input's kind is read once here; both passes open it as that kind, a log's records
  // are read once here and replayed to both.
  report->robot.kind = textio::detect_stream_file(robot_path);
  report->tracker.kind = textio::detect_stream_file(tracker_path);
  const std::unique_ptr<LogRecordReader> robot_log =
      report->robot.is_log() ? open_log_records(LogKind::robot, robot_path, log_options) : nullptr;
  const std::unique_ptr<LogRecordReader> tracker_log =
      report->tracker.is_log() ? open_log_records(LogKind::tracker, tracker_path, log_options) : nullptr;
  for (const LogRecordReader* log : {robot_log.get(), tracker_log.get()}) {
    if (log != nullptr && !log->error().empty()) return port::Error::input(log->error());
  }
  // Both passes in lib's capture front; the large fixed-size objects on the app's heap, once
  // (bounded whatever the input length).
  const auto workspace = std::make_unique<HostCaptureWorkspace>();
  CaptureOptions options;
  options.clock = clock_config;
  options.extraction = extraction_config;
  options.observer = observer;
  ClockMatchRecorder match;
  options.clock_observer = &match;
  FileRecordSource source(robot_path, tracker_path, robot_log.get(), tracker_log.get(), progress,
                          size_of(robot_path) + size_of(tracker_path));
  CaptureExtraction result;
  const Status status = extract_dataset_from_captures(source, options, workspace.get(), dataset, &result);
  if (!source.open_error().ok()) return source.open_error();
  // Pass 1: the clock.
  std::string error;
  report->clock = result.clock;
  report->clock_status = source.pass(1).finish(result.pass == CapturePass::clock ? status : Status::ok, &error);
  count_input(source.pass(1).robot_input(), result.decoding.robot_decoder, true, robot_log.get(), &report->robot);
  count_input(source.pass(1).tracker_input(), result.decoding.tracker_decoder, false, tracker_log.get(),
              &report->tracker);
  report->clock_stats = result.clock_stats;
  if (report->clock_status == Status::ok) report->clock_match = std::move(match.bins);
  if (report->clock_status == Status::invalid_argument && !error.empty()) return port::Error::input(error);
  const port::Error swapped = check_not_swapped(robot_path, tracker_path, *report);
  if (!swapped.ok()) return swapped;
  if (report->clock_status != Status::ok || source.opened() < 2) return port::Error{};
  // Pass 2: the samples.
  report->extraction_status = source.pass(2).finish(status, &error);
  report->counts = result.counts;
  if (report->extraction_status == Status::invalid_argument && !error.empty()) return port::Error::input(error);
  return port::Error{};
}

}  // namespace hivecal::streams
