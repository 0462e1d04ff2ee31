#include "hivecal/sync/capture_dataset.hpp"

#include <new>

namespace hivecal {
namespace {

/// A CaptureSource's bytes as records: every open decodes the newly opened streams with fresh
/// FrameRecordReaders (built in place: a reader is ~1.3 kB, and a pass needs two).
class FrameRecordSource final : public RecordSource {
 public:
  explicit FrameRecordSource(CaptureSource& bytes) : bytes_(bytes) {}
  FrameRecordSource(const FrameRecordSource&) = delete;
  FrameRecordSource& operator=(const FrameRecordSource&) = delete;
  ~FrameRecordSource() { end(); }

  Status open(RecordReader** robot, RecordReader** tracker) override {
    end();
    ByteReader* robot_bytes = nullptr;
    ByteReader* tracker_bytes = nullptr;
    const Status status = bytes_.open(&robot_bytes, &tracker_bytes);
    if (status != Status::ok) return status;
    robot_ = new (robot_storage_) FrameRecordReader(robot_bytes);
    tracker_ = new (tracker_storage_) FrameRecordReader(tracker_bytes);
    *robot = robot_;
    *tracker = tracker_;
    return Status::ok;
  }

 private:
  void end() {
    if (robot_ != nullptr) robot_->~FrameRecordReader();
    if (tracker_ != nullptr) tracker_->~FrameRecordReader();
    robot_ = nullptr;
    tracker_ = nullptr;
  }

  CaptureSource& bytes_;
  alignas(FrameRecordReader) unsigned char robot_storage_[sizeof(FrameRecordReader)];
  alignas(FrameRecordReader) unsigned char tracker_storage_[sizeof(FrameRecordReader)];
  FrameRecordReader* robot_ = nullptr;
  FrameRecordReader* tracker_ = nullptr;
};

}  // namespace

CaptureOptions make_capture_options(const RobotModel& nominal) {
  CaptureOptions options;
  options.clock = make_clock_sync_config(nominal);
  options.extraction = make_extraction_config(nominal);
  return options;
}

Status estimate_capture_clock(RecordSource& source, const CaptureOptions& options, CaptureWorkspaceBase* workspace,
                              CaptureExtraction* result) {
  if (workspace == nullptr || result == nullptr) return Status::invalid_argument;
  result->pass = CapturePass::clock;
  RecordReader* robot = nullptr;
  RecordReader* tracker = nullptr;
  result->status = source.open(&robot, &tracker);
  if (result->status != Status::ok) return result->status;
  ClockEstimatorBase* estimator = workspace->open_estimator(options.clock);
  result->status = estimate_clock_from_streams(*robot, *tracker, estimator, &result->clock, &result->decoding);
  result->clock_stats = estimator->stats();
  if (options.clock_observer != nullptr)
    options.clock_observer->on_clock_pass(*estimator, result->status, result->clock);
  workspace->close();
  return result->status;
}

Status extract_capture_samples(RecordSource& source, const CaptureOptions& options, CaptureWorkspaceBase* workspace,
                               DatasetBase* dataset, CaptureExtraction* result) {
  if (workspace == nullptr || dataset == nullptr || result == nullptr) return Status::invalid_argument;
  result->pass = CapturePass::extraction;
  RecordReader* robot = nullptr;
  RecordReader* tracker = nullptr;
  result->status = source.open(&robot, &tracker);
  if (result->status != Status::ok) return result->status;
  dataset->clear();
  SampleExtractorBase* extractor = workspace->open_extractor(options.extraction, result->clock, dataset);
  if (options.observer != nullptr) extractor->set_observer(options.observer);  // else the workspace's own, if any
  result->status = extract_samples_from_streams(*robot, *tracker, extractor, nullptr);
  result->counts = extractor->counts();
  workspace->close();
  return result->status;
}

Status extract_dataset_from_captures(RecordSource& source, const CaptureOptions& options,
                                     CaptureWorkspaceBase* workspace, DatasetBase* dataset, CaptureExtraction* result) {
  if (workspace == nullptr || dataset == nullptr || result == nullptr) return Status::invalid_argument;
  *result = CaptureExtraction();
  Status status = estimate_capture_clock(source, options, workspace, result);
  if (status != Status::ok) return status;
  status = extract_capture_samples(source, options, workspace, dataset, result);
  if (status != Status::ok) return status;
  result->pass = CapturePass::done;
  return Status::ok;
}

Status estimate_capture_clock(const RobotModel& nominal, CaptureSource& source, CaptureWorkspaceBase* workspace,
                              CaptureExtraction* result) {
  FrameRecordSource records(source);
  return estimate_capture_clock(records, make_capture_options(nominal), workspace, result);
}

Status extract_capture_samples(const RobotModel& nominal, CaptureSource& source, CaptureWorkspaceBase* workspace,
                               DatasetBase* dataset, CaptureExtraction* result) {
  FrameRecordSource records(source);
  return extract_capture_samples(records, make_capture_options(nominal), workspace, dataset, result);
}

Status extract_dataset_from_captures(const RobotModel& nominal, CaptureSource& source, CaptureWorkspaceBase* workspace,
                                     DatasetBase* dataset, CaptureExtraction* result) {
  FrameRecordSource records(source);
  return extract_dataset_from_captures(records, make_capture_options(nominal), workspace, dataset, result);
}

}  // namespace hivecal
