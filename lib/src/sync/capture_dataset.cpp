#include "hivecal/sync/capture_dataset.hpp"

namespace hivecal {

Status estimate_capture_clock(const RobotModel& nominal, CaptureSource& source, CaptureWorkspaceBase* workspace,
                              CaptureExtraction* result) {
  if (workspace == nullptr || result == nullptr) return Status::invalid_argument;
  result->pass = CapturePass::clock;
  ByteReader* robot = nullptr;
  ByteReader* tracker = nullptr;
  result->status = source.open(&robot, &tracker);
  if (result->status != Status::ok) return result->status;
  ClockEstimatorBase* estimator = workspace->open_estimator(make_clock_sync_config(nominal));
  result->status = estimate_clock_from_streams(*robot, *tracker, estimator, &result->clock, &result->decoding);
  workspace->close();
  return result->status;
}

Status extract_capture_samples(const RobotModel& nominal, CaptureSource& source, CaptureWorkspaceBase* workspace,
                               DatasetBase* dataset, CaptureExtraction* result) {
  if (workspace == nullptr || dataset == nullptr || result == nullptr) return Status::invalid_argument;
  result->pass = CapturePass::extraction;
  ByteReader* robot = nullptr;
  ByteReader* tracker = nullptr;
  result->status = source.open(&robot, &tracker);
  if (result->status != Status::ok) return result->status;
  dataset->clear();
  SampleExtractorBase* extractor = workspace->open_extractor(make_extraction_config(nominal), result->clock, dataset);
  result->status = extract_samples_from_streams(*robot, *tracker, extractor, nullptr);
  result->counts = extractor->counts();
  workspace->close();
  return result->status;
}

Status extract_dataset_from_captures(const RobotModel& nominal, CaptureSource& source,
                                     CaptureWorkspaceBase* workspace, DatasetBase* dataset,
                                     CaptureExtraction* result) {
  if (workspace == nullptr || dataset == nullptr || result == nullptr) return Status::invalid_argument;
  *result = CaptureExtraction();
  Status status = estimate_capture_clock(nominal, source, workspace, result);
  if (status != Status::ok) return status;
  status = extract_capture_samples(nominal, source, workspace, dataset, result);
  if (status != Status::ok) return status;
  result->pass = CapturePass::done;
  return Status::ok;
}

}  // namespace hivecal
