#include "stream_pipeline.hpp"

#include <cstring>
#include <memory>

#include "hivecal/port/capture_file.hpp"

namespace hivecal::streams {
namespace {

constexpr int kReadTimeoutMs = 200;

/// A port::ByteSource as the library's ByteReader: waits through read timeouts, keeps the
/// error text of a failed read.
class SourceReader final : public ByteReader {
 public:
  explicit SourceReader(port::ByteSource* source) : source_(source) {}
  Status read(std::uint8_t* out, std::size_t capacity, std::size_t* count) override {
    for (;;) {
      const port::ReadResult got = source_->read(out, capacity, kReadTimeoutMs);
      if (got.status == port::ReadStatus::data) {
        *count = got.bytes;
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
  const std::string& error() const { return error_; }

 private:
  port::ByteSource* source_;
  std::string error_;
};

/// The library's read_failed as this API reports it: invalid_argument with the message.
Status io_status(Status status, const SourceReader& robot, const SourceReader& tracker, std::string* error) {
  if (status != Status::read_failed) return status;
  *error = robot.error().empty() ? tracker.error() : robot.error();
  return Status::invalid_argument;
}

}  // namespace

Status estimate_clock(port::ByteSource* robot, port::ByteSource* tracker, ClockEstimatorBase* estimator,
                      ClockFit* fit, PassStats* stats, std::string* error) {
  SourceReader robot_reader(robot);
  SourceReader tracker_reader(tracker);
  const Status status = estimate_clock_from_streams(robot_reader, tracker_reader, estimator, fit, stats);
  return io_status(status, robot_reader, tracker_reader, error);
}

Status extract_samples(port::ByteSource* robot, port::ByteSource* tracker, SampleExtractorBase* extractor,
                       PassStats* stats, std::string* error) {
  SourceReader robot_reader(robot);
  SourceReader tracker_reader(tracker);
  const Status status = extract_samples_from_streams(robot_reader, tracker_reader, extractor, stats);
  return io_status(status, robot_reader, tracker_reader, error);
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
