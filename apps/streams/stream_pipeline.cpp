#include "stream_pipeline.hpp"

#include <cstring>
#include <memory>
#include <sys/stat.h>

#include "hivecal/port/capture_file.hpp"
#include "text_util.hpp"

namespace hivecal::streams {
namespace {

constexpr std::size_t kChunkBytes = 4096;  // one read: at most ~30 joint frames queued
constexpr int kReadTimeoutMs = 200;
constexpr int kLogRowsPerFill = 32;        // rows parsed per fill() of a CSV log
constexpr double kMaxLogTime_s = 1.8e13;   // microseconds still fit a u64 (and a double's integers)

/// Pops every queued record of `queue` into the estimator.
void drain_into(RecordSource* queue, ClockEstimatorBase* estimator) {
  for (const JointStateRecord& r : queue->joints()) estimator->push_robot(r);
  for (const TrackerPointRecord& r : queue->points()) estimator->push_tracker(r);
  queue->joints().clear();
  queue->points().clear();
}

/// Calls `progress` when another kProgressStepBytes of input have been read.
class ProgressTicker {
 public:
  ProgressTicker(const PassProgress& progress, int pass, const RecordSource& a, const RecordSource& b,
                 std::uint64_t total_bytes)
      : progress_(progress), pass_(pass), a_(a), b_(b), total_(total_bytes) {}
  void tick() {
    if (!progress_) return;
    const std::uint64_t done = a_.bytes_read() + b_.bytes_read();
    if (done < next_) return;
    next_ = done + kProgressStepBytes;
    progress_(pass_, done, total_);
  }
  void finish() {
    if (progress_) progress_(pass_, a_.bytes_read() + b_.bytes_read(), total_);
  }

 private:
  static constexpr std::uint64_t kProgressStepBytes = 256 * 1024;
  const PassProgress& progress_;
  int pass_;
  const RecordSource& a_;
  const RecordSource& b_;
  std::uint64_t total_;
  std::uint64_t next_ = 0;
};

/// Size of a file [bytes], 0 when unknown.
std::uint64_t file_bytes(const std::string& path) {
  struct stat info {};
  return ::stat(path.c_str(), &info) == 0 ? static_cast<std::uint64_t>(info.st_size) : 0;
}

Status io_failure(const RecordSource& queue, std::string* error) {
  *error = queue.error();
  return Status::invalid_argument;
}

}  // namespace

bool RecordQueue::fill() {
  std::uint8_t chunk[kChunkBytes];
  while (joints_.empty() && points_.empty() && !ended_ && source_ != nullptr) {
    const port::ReadResult got = source_->read(chunk, sizeof chunk, kReadTimeoutMs);
    if (got.status == port::ReadStatus::data) {
      decoder_.feed(chunk, got.bytes, *this);
    } else if (got.status == port::ReadStatus::end_of_stream) {
      ended_ = true;
    } else if (got.status == port::ReadStatus::error) {
      error_ = source_->name() + ": read failed: " + std::strerror(got.error_number);
      ended_ = true;
    }
  }
  return !joints_.empty() || !points_.empty();
}

bool LogRecordQueue::open() {
  opened_ = true;
  const textio::ParseResult r = kind_ == Kind::robot ? robot_.open(path_) : tracker_.open(path_);
  if (!r.ok) error_ = r.message;
  return r.ok;
}

bool LogRecordQueue::to_microseconds(double t_s, std::uint64_t* t_us) {
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

bool LogRecordQueue::read_row() {
  bool got_row = false;
  textio::ParseResult r;
  if (kind_ == Kind::robot) {
    textio::RobotLogRow row;
    r = robot_.next(&row, &got_row);
    if (r.ok && got_row) {
      JointStateRecord record;
      if (!to_microseconds(row.t_s, &record.timestamp_us)) return false;
      for (int j = 0; j < kJointCount; ++j) record.q_rad[j] = row.q_rad(j);
      joints_.push_back(record);
      ++stats_.joint_states;
    }
  } else {
    textio::TrackerLogRow row;
    r = tracker_.next(&row, &got_row);
    if (r.ok && got_row) {
      TrackerPointRecord record;
      if (!to_microseconds(row.t_s, &record.timestamp_us)) return false;
      for (int k = 0; k < 3; ++k) record.point_m[k] = row.point_m(k);
      record.status = row.status;
      points_.push_back(record);
      ++stats_.tracker_points;
    }
  }
  if (!r.ok) error_ = r.message;
  if (got_row) ++stats_.frames_ok;
  return r.ok && got_row;
}

bool LogRecordQueue::fill() {
  if (!opened_ && !open()) ended_ = true;
  for (int k = 0; k < kLogRowsPerFill && !ended_; ++k) {
    if (!read_row()) ended_ = true;
  }
  return !joints_.empty() || !points_.empty();
}

std::unique_ptr<RecordSource> open_record_source(const std::string& path, LogRecordQueue::Kind stream,
                                                 std::unique_ptr<port::ByteSource>* bytes, std::string* error) {
  if (textio::detect_stream_file(path) == textio::StreamFileKind::csv_log) {
    return std::make_unique<LogRecordQueue>(stream, path);
  }
  auto capture = std::make_unique<port::CaptureFileSource>(path);
  if (!capture->open(error)) return nullptr;
  *bytes = std::move(capture);
  return std::make_unique<RecordQueue>(bytes->get());
}

Status estimate_clock(RecordSource* robot, RecordSource* tracker, ClockEstimatorBase* estimator,
                      ClockFit* fit, PassStats* stats, std::string* error, const PassProgress& progress) {
  ProgressTicker ticker(progress, 1, *robot, *tracker, 0);
  // The estimator keeps the two streams apart: each source is read to its end in turn.
  for (RecordSource* queue : {robot, tracker}) {
    while (queue->fill()) {
      drain_into(queue, estimator);
      ticker.tick();
    }
    if (!queue->error().empty()) return io_failure(*queue, error);
  }
  ticker.finish();
  stats->robot_decoder = robot->decoder_stats();
  stats->tracker_decoder = tracker->decoder_stats();
  return estimator->estimate(fit);
}

Status extract_samples(RecordSource* robot, RecordSource* tracker, SampleExtractorBase* extractor,
                       PassStats* stats, std::string* error, const PassProgress& progress) {
  RecordSource& robot_queue = *robot;
  RecordSource& tracker_queue = *tracker;
  ProgressTicker ticker(progress, 2, robot_queue, tracker_queue, 0);
  Status result = Status::ok;
  auto note = [&result](Status s) {
    if (s != Status::ok) result = s;
  };
  for (;;) {
    if (robot_queue.joints().empty()) robot_queue.fill();
    if (tracker_queue.points().empty()) tracker_queue.fill();
    robot_queue.points().clear();   // a robot capture carries no tracker points (ignored if any)
    tracker_queue.joints().clear();
    const bool has_joint = !robot_queue.joints().empty();
    const bool has_point = !tracker_queue.points().empty();
    if (!has_joint && !has_point) break;
    ticker.tick();
    // Robot-clock order keeps the two streams within the extractor's rings.
    if (has_point && (!has_joint || extractor->clock().robot_us(static_cast<double>(
                                        tracker_queue.points().front().timestamp_us)) <=
                                        static_cast<double>(robot_queue.joints().front().timestamp_us))) {
      note(extractor->push_tracker(tracker_queue.points().front()));
      tracker_queue.points().pop_front();
    } else {
      note(extractor->push_robot(robot_queue.joints().front()));
      robot_queue.joints().pop_front();
    }
  }
  for (const RecordSource* queue : {robot, tracker})
    if (!queue->error().empty()) return io_failure(*queue, error);
  ticker.finish();
  note(extractor->finish());
  stats->robot_decoder = robot_queue.decoder_stats();
  stats->tracker_decoder = tracker_queue.decoder_stats();
  return result;
}

namespace {

/// The two inputs opened for one pass.
struct OpenInputs {
  std::unique_ptr<port::ByteSource> robot_bytes;
  std::unique_ptr<port::ByteSource> tracker_bytes;
  std::unique_ptr<RecordSource> robot;
  std::unique_ptr<RecordSource> tracker;

  bool open(const std::string& robot_path, const std::string& tracker_path, std::string* error) {
    robot = open_record_source(robot_path, LogRecordQueue::Kind::robot, &robot_bytes, error);
    if (robot == nullptr) return false;
    tracker = open_record_source(tracker_path, LogRecordQueue::Kind::tracker, &tracker_bytes, error);
    return tracker != nullptr;
  }
};

}  // namespace

bool extract_from_files(const std::string& robot_path, const std::string& tracker_path,
                        const ClockSyncConfig& clock_config, const ExtractionConfig& extraction_config,
                        DatasetBase* dataset, CaptureRunReport* report, std::string* error,
                        ExtractionObserver* observer, const PassProgress& progress) {
  const std::uint64_t total_bytes = file_bytes(robot_path) + file_bytes(tracker_path);
  PassProgress with_total;
  if (progress) {
    with_total = [&progress, total_bytes](int pass, std::uint64_t done, std::uint64_t) { progress(pass, done, total_bytes); };
  }
  report->robot_is_log = textio::detect_stream_file(robot_path) == textio::StreamFileKind::csv_log;
  report->tracker_is_log = textio::detect_stream_file(tracker_path) == textio::StreamFileKind::csv_log;
  // Large fixed-size objects: on the heap of the app, once (bounded whatever the input length).
  const auto estimator = std::make_unique<ClockEstimator<>>(clock_config);
  {
    OpenInputs inputs;
    if (!inputs.open(robot_path, tracker_path, error)) return false;
    report->clock_status = estimate_clock(inputs.robot.get(), inputs.tracker.get(), estimator.get(), &report->clock,
                                          &report->decoding, error, with_total);
    report->clock_stats = estimator->stats();
    if (report->clock_status == Status::invalid_argument && !error->empty()) return false;
    if (report->clock_status != Status::ok) return true;
  }
  const auto extractor = std::make_unique<SampleExtractor<>>(extraction_config, report->clock, dataset);
  extractor->set_observer(observer);
  OpenInputs inputs;
  if (!inputs.open(robot_path, tracker_path, error)) return false;
  PassStats second;
  report->extraction_status =
      extract_samples(inputs.robot.get(), inputs.tracker.get(), extractor.get(), &second, error, with_total);
  report->counts = extractor->counts();
  return report->extraction_status != Status::invalid_argument || error->empty();
}

}  // namespace hivecal::streams
