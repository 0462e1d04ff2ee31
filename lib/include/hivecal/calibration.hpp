// The calibration job, one entry for the command-line tool, the firmware and the tests:
//   blunder screen (consensus over point triples) -> split -> baseline (start geometry, tool
//   point and base fitted on the training samples) -> the solver
//   stages of CalibrationOptions::method (ABC / GSA on the link lengths, then or instead
//   Levenberg-Marquardt on the full model) -> train/test errors of every stage -> the w-test
//   of every pose (data snooping: blunders set aside one at a time, the job rerun until the
//   set is stable; solve/reliability.hpp). cross_validate() runs the same job per fold. Method: docs/robust.md.
// Like ruckig's Ruckig / InputParameter / Result: options in, a caller-sized workspace, one
// result struct out. No heap, no clock: a caller that wants stage timings takes them in its
// CalibrationObserver. Method and figures: docs/architecture.md, "The calibration job".
// The job's types have their own headers (hivecal/job/): the options, the result, the
// workspace and the joint-term families; this one includes them all and is the entry to use.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/core/status.hpp"
#include "hivecal/job/calibration_options.hpp"
#include "hivecal/job/calibration_result.hpp"
#include "hivecal/job/calibration_workspace.hpp"
#include "hivecal/job/joint_term_families.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/solve/objective.hpp"
#include "hivecal/solve/reliability.hpp"

namespace hivecal {

/// The job's work outside its stages, as CalibrationObserver::on_phase reports it.
enum class CalibrationPhase : std::uint8_t {
  screen,        ///< the start geometry's consensus screen for gross blunders (once per job)
  baseline,      ///< the uncalibrated baseline's tool point and base fit (once per run)
  blunder_test,  ///< the w-test of a run's calibration, which decides whether the job runs again
};

/// Optional hooks: stage begin and end and the phases between them (for timings, which lib
/// does not take) and the solvers' per-iteration progress. The defaults do nothing and never
/// cancel.
class CalibrationObserver : public ProgressObserver, public LmObserver {
 public:
  /// When `phase` begins (`ended` false) and when it ends (true; also when it failed).
  virtual void on_phase(CalibrationPhase phase, bool ended) {
    (void)phase;
    (void)ended;
  }
  /// Before stage `index` with `solver` starts (its cost is built inside the stage).
  virtual void on_stage_begin(std::size_t index, CalibrationSolver solver) {
    (void)index;
    (void)solver;
  }
  /// After stage `index` succeeded (not called for a failing stage).
  virtual void on_stage_end(std::size_t index, const CalibrationStage& stage) {
    (void)index;
    (void)stage;
  }
  void on_iteration(const SolverProgress& progress) override { (void)progress; }
  bool on_iteration(const LmIterationInfo& info) override {
    (void)info;
    return true;
  }

 protected:
  CalibrationObserver() = default;
  CalibrationObserver(const CalibrationObserver&) = default;
  CalibrationObserver& operator=(const CalibrationObserver&) = default;
  ~CalibrationObserver() = default;
};

/// Runs the job of `options` on `*dataset` from `start` (geometry and tool): screens the
/// samples for blunders (unless options.keep_outliers), sets them aside in the dataset
/// (DatasetBase::set_aside), splits the rest (in place, seeded), fits the baseline, runs the
/// stages, tests every sample against the final calibration and, while that changes the set
/// aside, runs again; fills *result. The job always starts from the samples in the order of
/// add(): the same dataset gives the same result, and a blunder set aside gives the bits of
/// the same set with the blunder never added. `observer` may be null. Returns ok (LM's
/// not_converged counts as a result: its last point is used), or the failure, with
/// result->step naming the step that failed:
///  - input: invalid_argument (a null pointer, an unknown method or parameter set, a start
///    model that check_joint_layout refuses, compliance enabled without an LM stage or with
///    terms that default_compliance_terms or check_compliance refuse), dataset_empty,
///    joint_count_mismatch (a sample reads a joint beyond the model's: readings_fit_joint_count);
///  - split: invalid_argument (the fraction leaves no training sample);
///  - baseline: too_few_samples / degenerate_geometry (fewer than 3 non-collinear points: not
///    even the base frame is determined), the errors of fit_base_to_tracker;
///  - gsa / abc / lm (LM+compliance too): the stage's own error (calibrate_paper6_gsa/abc, calibrate_lm), e.g.
///    too_few_samples (LM: not even with its weakest directions dropped do fewer parameters
///    remain than 3 N equations), population_out_of_range (population
///    above the workspace's capacity), dataset_full (more training samples than the
///    workspace's cost holds), solver_cancelled (the observer stopped LM).
/// Parameters LM finds unidentifiable keep their start values (a hybrid's LM reruns from the
/// start values of what it dropped). With options.detect_controller_frames the job runs up to
/// three times (fitted frames, the controller's, the fitted again when those are rejected);
/// result->frames_test says what it found. *result is always written when it is not null.
Status calibrate(const RobotModel& start, DatasetBase* dataset, const CalibrationOptions& options,
                 CalibrationWorkspaceBase* workspace, CalibrationResult* result,
                 CalibrationObserver* observer = nullptr);

/// What the final stage of `result` estimated: LM's kept parameters (with kOtherTargetTools
/// when it estimated the other targets' tool points), or a population stage's link lengths
/// and base: the parameters test_for_blunders tests the fit with.
ParamMask calibration_estimated_mask(const CalibrationResult& result);

/// The w-test of the final calibration of `result` on `dataset` as the job left it (its training
/// samples fitted, its test and set-aside samples predicted) with `options`' test settings: each
/// pose to `visitor` (a report's per-pose w and uncontrolled poses). Errors: invalid_argument
/// (no stage ran), those of test_for_blunders.
Status test_final_calibration(const CalibrationResult& result, const DatasetBase& dataset,
                              const CalibrationOptions& options, ReliabilityWorkspace* workspace,
                              UnitTestVisitor* visitor, BlunderTestSummary* summary);

/// Folds a cross-validation holds at most (leave-one-out on up to this many samples) [-].
inline constexpr std::size_t kMaxCrossValidationFolds = 128;

/// One fold of a cross-validation.
struct CrossValidationFold {
  std::size_t train_count = 0;  ///< samples it was calibrated on [-]
  ErrorStats test;              ///< errors of its final stage on its held-out samples [m]
  ErrorStats train;             ///< errors of its final stage on its training samples [m]
  ErrorStats baseline_test;     ///< errors of its uncalibrated baseline on its held-out samples [m]
};

/// What cross_validate() measured.
struct CrossValidationResult {
  Status status = Status::invalid_argument;             ///< ok, or why it stopped
  std::size_t fold_count = 0;                           ///< folds run [-]
  CrossValidationFold folds[kMaxCrossValidationFolds];  ///< per fold, in fold order
  std::size_t sample_count = 0;                         ///< samples split into folds (blunders left out) [-]
  double mae_3d_m = 0.0;                                ///< 3-D MAE over every held-out sample of every fold [m]
  double baseline_mae_3d_m = 0.0;                       ///< the same for the uncalibrated baseline of each fold [m]
  double fold_mae_3d_mean_m = 0.0;                      ///< mean of the folds' 3-D MAE [m]
  double fold_mae_3d_max_m = 0.0;                       ///< largest fold 3-D MAE [m]
};

/// The options `result` was calibrated with: `options` with the frames its test chose
/// (ControllerFramesTest: the controller's when adopted) and no test left to make; a second
/// job with them (cross_validate's) runs once instead of repeating the test.
CalibrationOptions options_with_chosen_frames(const CalibrationOptions& options, const CalibrationResult& result);

/// K-fold cross-validation of the job of `options` (folds = 0: leave-one-out): unless
/// options.keep_outliers, first the whole job on every sample finds the blunders, which stay
/// aside; then the kept samples in the order of add() are shuffled with options.seed (as
/// DatasetBase::split_fold) and each fold is calibrated on the other folds (no blunder search
/// and no split of its own) and tested on its own samples; with options.detect_controller_frames
/// the folds keep the frames that whole job chose. `scratch` receives each run in turn
/// (the last fold's at the end). Folds and leave-one-out are over poses
/// (DatasetBase::pose_count: with several targets a pose's samples stay together). Errors:
/// those of calibrate() (the first failing fold's, in cv->status too); invalid_argument
/// (folds == 1, more folds than poses, or more than kMaxCrossValidationFolds).
Status cross_validate(const RobotModel& start, DatasetBase* dataset, const CalibrationOptions& options,
                      std::size_t folds, CalibrationWorkspaceBase* workspace, CalibrationResult* scratch,
                      CrossValidationResult* cv, CalibrationObserver* observer = nullptr);

}  // namespace hivecal
