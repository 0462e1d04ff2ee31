#include "stream_pipeline.hpp"

#include <cstring>
#include <memory>

#include "hivecal/port/capture_file.hpp"

namespace hivecal::streams {
namespace {

constexpr std::size_t kChunkBytes = 4096;  // one read: at most ~30 joint frames queued
constexpr int kReadTimeoutMs = 200;

/// Pops every queued record of `queue` into the estimator.
void drain_into(RecordQueue* queue, ClockEstimatorBase* estimator) {
  for (const JointStateRecord& r : queue->joints()) estimator->push_robot(r);
  for (const TrackerPointRecord& r : queue->points()) estimator->push_tracker(r);
  queue->joints().clear();
  queue->points().clear();
}

Status io_failure(const RecordQueue& queue, std::string* error) {
  *error = queue.error();
  return Status::invalid_argument;
}

}  // namespace

bool RecordQueue::fill() {
  std::uint8_t chunk[kChunkBytes];
  while (joints_.empty() && points_.empty() && !ended_) {
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

Status estimate_clock(port::ByteSource* robot, port::ByteSource* tracker, ClockEstimatorBase* estimator,
                      ClockFit* fit, PassStats* stats, std::string* error) {
  RecordQueue robot_queue(robot);
  RecordQueue tracker_queue(tracker);
  // The estimator keeps the two streams apart: each source is read to its end in turn.
  for (RecordQueue* queue : {&robot_queue, &tracker_queue}) {
    while (queue->fill()) drain_into(queue, estimator);
    if (!queue->error().empty()) return io_failure(*queue, error);
  }
  stats->robot_decoder = robot_queue.decoder_stats();
  stats->tracker_decoder = tracker_queue.decoder_stats();
  return estimator->estimate(fit);
}

Status extract_samples(port::ByteSource* robot, port::ByteSource* tracker, SampleExtractorBase* extractor,
                       PassStats* stats, std::string* error) {
  RecordQueue robot_queue(robot);
  RecordQueue tracker_queue(tracker);
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
  for (const RecordQueue* queue : {&robot_queue, &tracker_queue})
    if (!queue->error().empty()) return io_failure(*queue, error);
  note(extractor->finish());
  stats->robot_decoder = robot_queue.decoder_stats();
  stats->tracker_decoder = tracker_queue.decoder_stats();
  return result;
}

bool extract_from_captures(const std::string& robot_capture, const std::string& tracker_capture,
                           const ClockSyncConfig& clock_config, const ExtractionConfig& extraction_config,
                           DatasetBase* dataset, CaptureRunReport* report, std::string* error,
                           ExtractionObserver* observer) {
  // Large fixed-size objects: on the heap of the app, once (bounded whatever the capture).
  const auto estimator = std::make_unique<ClockEstimator<>>(clock_config);
  {
    port::CaptureFileSource robot(robot_capture);
    port::CaptureFileSource tracker(tracker_capture);
    if (!robot.open(error) || !tracker.open(error)) return false;
    report->clock_status = estimate_clock(&robot, &tracker, estimator.get(), &report->clock, &report->decoding, error);
    report->clock_stats = estimator->stats();
    if (report->clock_status == Status::invalid_argument && !error->empty()) return false;
    if (report->clock_status != Status::ok) return true;
  }
  const auto extractor = std::make_unique<SampleExtractor<>>(extraction_config, report->clock, dataset);
  extractor->set_observer(observer);
  port::CaptureFileSource robot(robot_capture);
  port::CaptureFileSource tracker(tracker_capture);
  if (!robot.open(error) || !tracker.open(error)) return false;
  PassStats second;
  report->extraction_status = extract_samples(&robot, &tracker, extractor.get(), &second, error);
  report->counts = extractor->counts();
  return report->extraction_status != Status::invalid_argument || error->empty();
}

}  // namespace hivecal::streams
