// From a robot and a tracker stream to a dataset: the two passes of capture_pipeline.hpp over
// streams the caller can open again at their start: captures as bytes (files, flash,
// semihosting: CaptureSource) or records from any source (a host's text logs: RecordSource):
//   pass 1: records of both streams -> ClockEstimator -> clock relation;
//   pass 2: the records again -> SampleExtractor -> quasi-static samples in a dataset.
// This is the one capture front: the firmware and the command-line tool both call it.
// The estimator and the extractor are never alive together: CaptureWorkspace builds them one
// after the other in one arena (placement new), so that a small target pays for the larger.
// Then calibration.hpp's calibrate() runs the job on the dataset.
#pragma once

#include <cstddef>
#include <cstdint>
#include <new>

#include "hivecal/core/status.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/sync/capture_pipeline.hpp"
#include "hivecal/sync/clock_sync.hpp"
#include "hivecal/sync/sample_extraction.hpp"
#include "hivecal/wire/byte_reader.hpp"

namespace hivecal {

/// Opens (again) both captures at their first byte; implemented over files on a host and
/// over semihosting or flash on a target.
class CaptureSource {
 public:
  /// The two readers, positioned at the start. Errors: read_failed (cannot be (re)opened).
  virtual Status open(ByteReader** robot, ByteReader** tracker) = 0;

 protected:
  CaptureSource() = default;
  CaptureSource(const CaptureSource&) = default;
  CaptureSource& operator=(const CaptureSource&) = default;
  ~CaptureSource() = default;
};

/// Opens (again) both streams at their first record; a host's text logs or captures with its
/// own progress reporting. Each pass opens once (pass 1, then pass 2).
class RecordSource {
 public:
  /// The two readers, positioned at the start. Errors: read_failed (cannot be (re)opened).
  virtual Status open(RecordReader** robot, RecordReader** tracker) = 0;

 protected:
  RecordSource() = default;
  RecordSource(const RecordSource&) = default;
  RecordSource& operator=(const RecordSource&) = default;
  ~RecordSource() = default;
};

/// Told the end of pass 1 while its estimator still holds the profiles, e.g. to describe what
/// the clock fit matched (ClockEstimatorBase::match_profiles, for a report).
class ClockPassObserver {
 public:
  /// `status`: the pass's outcome; `fit`: its clock relation (meaningful when status is ok).
  virtual void on_clock_pass(const ClockEstimatorBase& estimator, Status status, const ClockFit& fit) = 0;

 protected:
  ClockPassObserver() = default;
  ClockPassObserver(const ClockPassObserver&) = default;
  ClockPassObserver& operator=(const ClockPassObserver&) = default;
  ~ClockPassObserver() = default;
};

/// How the passes run.
struct CaptureOptions {
  ClockSyncConfig clock;        ///< pass 1's settings (make_clock_sync_config)
  ExtractionConfig extraction;  ///< pass 2's settings (make_extraction_config)
  ExtractionObserver* observer =
      nullptr;  ///< told each kept sample and each drop of pass 2; null: none (or one the workspace installs)
  ClockPassObserver* clock_observer = nullptr;  ///< told the end of pass 1; null: none
};

/// The options of a robot with `nominal` geometry (the speed model of both passes).
CaptureOptions make_capture_options(const RobotModel& nominal);

/// The passes over the captures (CaptureExtraction::pass is the last one reached).
enum class CapturePass : std::uint8_t { clock, extraction, done };

/// What the passes found.
struct CaptureExtraction {
  Status status = Status::ok;             ///< ok, or why `pass` failed
  CapturePass pass = CapturePass::clock;  ///< done after both passes, else the pass that failed
  StreamPassStats decoding;               ///< decoder counters of pass 1
  ClockFit clock;                         ///< the clock relation of pass 1
  ClockProfileStats clock_stats;          ///< what went into pass 1's profiles (a failed fit's explanation)
  ExtractionCounts counts;                ///< what pass 2 kept and dropped
};

/// Capacity-erased workspace: builds the estimator or the extractor in its arena.
class CaptureWorkspaceBase {
 public:
  CaptureWorkspaceBase(const CaptureWorkspaceBase&) = delete;
  CaptureWorkspaceBase& operator=(const CaptureWorkspaceBase&) = delete;

  /// Ends any open pass, builds a clock estimator with `config` in the arena.
  virtual ClockEstimatorBase* open_estimator(const ClockSyncConfig& config) = 0;
  /// Ends any open pass, builds a sample extractor writing into `dataset` in the arena.
  virtual SampleExtractorBase* open_extractor(const ExtractionConfig& config, const ClockFit& clock,
                                              DatasetBase* dataset) = 0;
  /// Ends the open pass (its object is destroyed).
  virtual void close() = 0;

 protected:
  CaptureWorkspaceBase() = default;
  ~CaptureWorkspaceBase() = default;
};

/// A workspace whose clock estimator holds `ClockRobotKnots` robot knots and
/// `ClockTrackerPoints` tracker points (the clock fit rests on that much of the session's
/// start), and whose extractor keeps `RobotHistory` robot records and `TrackerHistory`
/// tracker points (the quasi-static window plus the lag between the streams).
template <std::size_t ClockRobotKnots, std::size_t ClockTrackerPoints, std::size_t RobotHistory,
          std::size_t TrackerHistory>
class CaptureWorkspace final : public CaptureWorkspaceBase {
 public:
  using Estimator = ClockEstimator<ClockRobotKnots, ClockTrackerPoints>;  ///< pass 1 object
  using Extractor = SampleExtractor<RobotHistory, TrackerHistory>;        ///< pass 2 object
  /// Bytes of the arena: the larger of the two.
  static constexpr std::size_t kArenaBytes = sizeof(Estimator) > sizeof(Extractor) ? sizeof(Estimator)
                                                                                   : sizeof(Extractor);

  CaptureWorkspace() = default;
  ~CaptureWorkspace() { close(); }

  ClockEstimatorBase* open_estimator(const ClockSyncConfig& config) override {
    close();
    estimator_ = new (arena_) Estimator(config);
    return estimator_;
  }
  SampleExtractorBase* open_extractor(const ExtractionConfig& config, const ClockFit& clock,
                                      DatasetBase* dataset) override {
    close();
    extractor_ = new (arena_) Extractor(config, clock, dataset);
    return extractor_;
  }
  void close() override {
    if (estimator_ != nullptr) estimator_->~Estimator();
    if (extractor_ != nullptr) extractor_->~Extractor();
    estimator_ = nullptr;
    extractor_ = nullptr;
  }

 private:
  alignas(alignof(std::max_align_t)) unsigned char arena_[kArenaBytes];
  Estimator* estimator_ = nullptr;  // the open pass's object (at most one is set), built in arena_
  Extractor* extractor_ = nullptr;
};

/// Pass 1: opens the streams and estimates the clock relation into result->clock,
/// result->decoding and result->clock_stats (then tells options.clock_observer). Errors: those of
/// source.open and estimate_clock_from_streams (read_failed, clock_fit_failed, ...);
/// result->pass = clock.
Status estimate_capture_clock(RecordSource& source, const CaptureOptions& options, CaptureWorkspaceBase* workspace,
                              CaptureExtraction* result);

/// Pass 2: opens the streams again and extracts the quasi-static samples through
/// result->clock into *dataset (emptied first); result->counts. Errors: those of source.open
/// and extract_samples_from_streams (dataset_full, read_failed); result->pass = extraction.
Status extract_capture_samples(RecordSource& source, const CaptureOptions& options, CaptureWorkspaceBase* workspace,
                               DatasetBase* dataset, CaptureExtraction* result);

/// Both passes: *result is reset, then pass = done on success. Errors: invalid_argument (a null
/// pointer), and those of the two passes.
Status extract_dataset_from_captures(RecordSource& source, const CaptureOptions& options,
                                     CaptureWorkspaceBase* workspace, DatasetBase* dataset, CaptureExtraction* result);

/// The three above over captures as bytes, with make_capture_options(nominal): each open of
/// `source` is decoded by FrameRecordReaders. The same bits as the record versions.
Status estimate_capture_clock(const RobotModel& nominal, CaptureSource& source, CaptureWorkspaceBase* workspace,
                              CaptureExtraction* result);
Status extract_capture_samples(const RobotModel& nominal, CaptureSource& source, CaptureWorkspaceBase* workspace,
                               DatasetBase* dataset, CaptureExtraction* result);
Status extract_dataset_from_captures(const RobotModel& nominal, CaptureSource& source, CaptureWorkspaceBase* workspace,
                                     DatasetBase* dataset, CaptureExtraction* result);

}  // namespace hivecal
