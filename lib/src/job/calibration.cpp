// The calibration job's entry (calibration.hpp): the input checks, the runs until the blunder
// search's set aside is stable, the test of the controller's frames and the cross-validation;
// the stages of a run are stages.cpp's.
#include "hivecal/calibration.hpp"

#include <cmath>
#include <new>

#include "hivecal/core/distributions.hpp"
#include "job/blunder_search.hpp"
#include "job/job.hpp"

namespace hivecal {
namespace {

using detail::blunder_limit;
using detail::blunder_test_loss;
using detail::compliance_start;
using detail::fail;
using detail::index_span;
using detail::keep_common;
using detail::plan_for;
using detail::report_phase;
using detail::run_split;
using detail::same_indices;
using detail::screen;
using detail::search_blunders;
using detail::test_blunder_limit;

bool known(const CalibrationOptions& options) {
  return options.method <= CalibrationMethod::all && options.params <= CalibrationParams::paper &&
         (!(options.base_known || options.tool_known) ||
          options.method == CalibrationMethod::lm);  // ABC/GSA fit their own
}

/// Resets *result in place (no 5 KB temporary on the stack).
CalibrationResult& reset(CalibrationResult* result) {
  result->~CalibrationResult();
  return *new (result) CalibrationResult();
}

/// The compliance options are usable: off, or on with an LM stage and terms, and the method's
/// stages and the terms' stages within the result's kMaxCalibrationStages (a build of few terms
/// holds fewer stages: a small arm's terms of both families could ask for one more).
bool compliance_usable(const RobotModel& start, const CalibrationOptions& options) {
  if (!options.compliance.enabled) return true;
  ComplianceModel model;
  const detail::StagePlan plan = plan_for(options.method);
  if (!plan.lm || compliance_start(start, options.compliance, all_joint_term_families(kJointTermFamilyCount), &model) !=
                      Status::ok) {
    return false;
  }
  const int stages = int{plan.gsa} + int{plan.abc} + 1 + plan_joint_term_stages(model).count;
  return stages <= static_cast<int>(kMaxCalibrationStages);
}

/// Input checks shared by calibrate() and cross_validate().
Status check_inputs(const RobotModel& start, DatasetBase* dataset, const CalibrationOptions& options,
                    CalibrationWorkspaceBase* workspace, CalibrationResult* r) {
  if (dataset == nullptr || workspace == nullptr || !known(options) || check_joint_layout(start) != Status::ok ||
      !compliance_usable(start, options)) {
    return fail(r, CalibrationStep::input, Status::invalid_argument);
  }
  dataset->set_aside(Span<const std::uint32_t>());
  if (dataset->size() == 0) return fail(r, CalibrationStep::input, Status::dataset_empty);
  if (!readings_fit_joint_count(dataset->samples(), start.joint_count)) {
    return fail(r, CalibrationStep::input, Status::joint_count_mismatch);
  }
  return Status::ok;
}

/// One run of the job with `aside` set aside: split, baseline, stages.
Status run_once(const RobotModel& start, DatasetBase* dataset, const CalibrationOptions& options,
                CalibrationWorkspaceBase* workspace, CalibrationResult* result, CalibrationObserver* observer,
                Span<const std::uint32_t> aside) {
  CalibrationResult& r = reset(result);
  dataset->set_aside(aside);
  r.reading_noise = repeated_reading_noise(dataset->samples());  // in the order of add(), before the split reorders
  const Status status = dataset->split(options.train_fraction, options.seed);
  if (status != Status::ok) return fail(&r, CalibrationStep::split, status);
  return run_split(start, dataset, options, workspace, &r, observer);
}

/// The job with the frames `options` say (fitted, or known): the screen, the runs and the
/// blunder search.
Status run_job(const RobotModel& start, DatasetBase* dataset, const CalibrationOptions& options,
               CalibrationWorkspaceBase* workspace, CalibrationResult* result, CalibrationObserver* observer) {
  Status status = check_inputs(start, dataset, options, workspace, &reset(result));
  if (status != Status::ok) return status;
  if (options.keep_outliers) return run_once(start, dataset, options, workspace, result, observer, {});
  // The two lists live in the workspace (2.6 kB: not on a small target's stack).
  CalibrationOutlierList& aside = workspace->outlier_list(0);
  CalibrationOutlierList& tested = workspace->outlier_list(1);
  report_phase(observer, CalibrationPhase::screen, false);
  status = screen(start, dataset, options, *workspace, &aside);
  report_phase(observer, CalibrationPhase::screen, true);
  if (status != Status::ok) return fail(&reset(result), CalibrationStep::baseline, status);
  // Rerun until the w-test of the calibration sets aside what the run left out: a sample the
  // start geometry's screen flagged comes back when the calibration explains it.
  constexpr std::size_t kMaxRounds = 4;
  BlunderVerdict verdict = BlunderVerdict::not_searched;
  BlunderTestSummary summary;
  std::size_t round = 0;
  bool undecided = false;  // the runs did not agree within kMaxRounds
  while (true) {
    status = run_once(start, dataset, options, workspace, result, observer, index_span(aside));
    if (status != Status::ok) return status;
    ++round;
    report_phase(observer, CalibrationPhase::blunder_test, false);
    verdict = search_blunders(dataset, options, start, *workspace, *result, &tested, &summary);
    report_phase(observer, CalibrationPhase::blunder_test, true);
    if (verdict == BlunderVerdict::not_searched || same_indices(tested, aside) || undecided) break;
    if (round < kMaxRounds) {
      aside = tested;
      continue;
    }
    // No agreement: a pose at the threshold fails the test while fitted and passes when left
    // out (the split moves with it), round after round. What the last two tests did not both
    // flag is kept (a blunder is never made up), and one more run and test are of that set; a
    // pose the final test still flags stays, and the verdict says so.
    undecided = true;
    const std::size_t last_aside = aside.count;
    keep_common(tested, &aside);
    if (aside.count == last_aside) break;  // the last run was of this set already
  }
  // The residuals reported are the final calibration's (of the set the run left out), the w
  // the last test's.
  CalibrationResult& r = *result;
  r.outlier_count = 0;
  const CalibrationStage& final_stage = r.stages[r.stage_count - 1];
  for (const Sample& s : dataset->set_aside()) {
    CalibrationOutlier& o = r.outliers[r.outlier_count++];
    o = CalibrationOutlier{
        s.index, (final_stage.base_to_tracker.apply(fk_sample_point(final_stage.model, s)) - s.point_m).norm()};
    for (const CalibrationOutlier& t : Span<const CalibrationOutlier>(tested.items, tested.count)) {
      if (t.index == s.index) {
        o.w = t.w;
        o.critical_w = t.critical_w;
      }
    }
  }
  r.blunder_verdict = r.outlier_count > 0 && verdict == BlunderVerdict::clean ? BlunderVerdict::removed : verdict;
  if (undecided && verdict == BlunderVerdict::clean && !same_indices(tested, aside)) {
    r.blunder_verdict = BlunderVerdict::at_threshold;
  }
  r.blunder_test = summary;
  r.blunder_limit = blunder_limit(*dataset, options);
  r.test_blunder_limit = test_blunder_limit(*dataset, options);
  r.outlier_rounds = round;
  return Status::ok;
}

/// A fitted base within the gate of the identity (kControllerBaseGate_m, _rad).
bool near_identity(const RigidTransform& base) {
  // |R - I|_F / sqrt(2) is the rotation angle to first order (2 sin(angle / 2) exactly).
  const double angle_rad = (base.rotation - Mat3::Identity()).norm() / std::sqrt(2.0);
  return base.translation_m.norm() <= kControllerBaseGate_m && angle_rad <= kControllerBaseGate_rad;
}

/// The measurement noise per axis the controller's frames must explain the data to: the
/// tracker's scatter over repeated readings when the input has them, else the stated one
/// (CalibrationOptions::measurement_sigma_m, else the blunder test's tracker sigma) [m].
double frames_noise_sigma_m(const CalibrationResult& r, const CalibrationOptions& options) {
  if (r.reading_noise.measured()) return r.reading_noise.sigma_m;
  return options.measurement_sigma_m > 0.0 ? options.measurement_sigma_m : options.blunder_test.tracker_sigma_m;
}

/// The test of the known frames' run (the result's, ended with `known_status`) after the
/// fitted frames' run that set aside `fitted_aside` samples.
ControllerFramesTest test_controller_frames(Status known_status, std::size_t fitted_aside, const CalibrationResult& r,
                                            const CalibrationOptions& options) {
  ControllerFramesTest test;
  test.tested = true;
  test.status = known_status;
  // Known frames that explain the data only with more of it set aside as blunders do not.
  if (test.status == Status::ok && r.outlier_count > fitted_aside) test.status = Status::invalid_argument;
  if (test.status == Status::ok && r.lm.residual_dof < 1) test.status = Status::too_few_samples;
  if (test.status != Status::ok) return test;
  const double dof = static_cast<double>(r.lm.residual_dof);
  test.residual_sigma_m = r.lm.residual_sigma_m;
  test.noise_sigma_m = frames_noise_sigma_m(r, options);
  test.critical_sigma_m =
      test.noise_sigma_m * std::sqrt(math::chi_square_upper_quantile(kControllerFramesAlpha, dof) / dof);
  test.adopted = test.residual_sigma_m <= test.critical_sigma_m;
  return test;
}

/// Whether the job tests the controller's frames (CalibrationOptions::detect_controller_frames).
bool detects_controller_frames(const CalibrationOptions& options) {
  const bool ends_in_lm = plan_for(options.method).lm && options.method != CalibrationMethod::all;  // not a comparison
  return options.detect_controller_frames && !options.base_known && !options.tool_known && ends_in_lm;
}

/// `options` without the test: the frames fitted.
CalibrationOptions fitted_frames(const CalibrationOptions& options) {
  CalibrationOptions fitted = options;
  fitted.detect_controller_frames = false;
  return fitted;
}

/// Sets the controller's frames in *o: the base the identity, the tool points the start
/// model's, LM only (ABC and GSA fit their own base).
void set_controller_frames(CalibrationOptions* o) {
  o->method = CalibrationMethod::lm;
  o->base_known = true;
  o->known_base_to_tracker = RigidTransform{};
  o->tool_known = true;
}

/// The job with the frames test (detects_controller_frames). Not inlined: its copies of the
/// options stay off the stack of a job without it (the firmware's).
[[gnu::noinline]] Status calibrate_detecting_frames(const RobotModel& start, DatasetBase* dataset,
                                                    const CalibrationOptions& options,
                                                    CalibrationWorkspaceBase* workspace, CalibrationResult* result,
                                                    CalibrationObserver* observer) {
  const CalibrationOptions fitted = fitted_frames(options);
  Status status = run_job(start, dataset, fitted, workspace, result, observer);
  const CalibrationStage* final_stage = result->final_stage();
  if (status != Status::ok || !result->has_lm || final_stage == nullptr ||
      !near_identity(final_stage->base_to_tracker)) {
    return status;
  }
  const std::size_t fitted_aside = result->outlier_count;
  CalibrationOptions known = fitted;
  set_controller_frames(&known);
  status = run_job(start, dataset, known, workspace, result, observer);
  const ControllerFramesTest test = test_controller_frames(status, fitted_aside, *result, options);
  if (!test.adopted) status = run_job(start, dataset, fitted, workspace, result, observer);  // the same bits again
  result->frames_test = test;
  return status;
}

}  // namespace

CalibrationResult::CalibrationResult() = default;

ParamMask calibration_estimated_mask(const CalibrationResult& r) {
  const CalibrationStage& final_stage = r.stages[r.stage_count - 1];
  if (final_stage.solver != CalibrationSolver::lm) return lm_param_mask(LmParamSet::link_lengths, 0, final_stage.model);
  ParamMask mask = r.lm.identifiability.kept_mask;
  for (const Vec3& sigma : r.lm.other_tools_sigma_m) {
    if (sigma.squaredNorm() > 0.0) mask |= kOtherTargetTools;
  }
  return mask;
}

Status calibrate(const RobotModel& start, DatasetBase* dataset, const CalibrationOptions& options,
                 CalibrationWorkspaceBase* workspace, CalibrationResult* result, CalibrationObserver* observer) {
  if (result == nullptr) return Status::invalid_argument;
  if (detects_controller_frames(options)) {
    return calibrate_detecting_frames(start, dataset, options, workspace, result, observer);
  }
  return run_job(start, dataset, options, workspace, result, observer);  // run_job reads no detect flag
}

CalibrationOptions options_with_chosen_frames(const CalibrationOptions& options, const CalibrationResult& result) {
  CalibrationOptions chosen = fitted_frames(options);
  if (result.frames_test.adopted) set_controller_frames(&chosen);
  return chosen;
}

Status test_final_calibration(const CalibrationResult& result, const DatasetBase& dataset,
                              const CalibrationOptions& options, ReliabilityWorkspace* workspace,
                              UnitTestVisitor* visitor, BlunderTestSummary* summary) {
  const CalibrationStage* final_stage = result.final_stage();
  if (final_stage == nullptr || workspace == nullptr || summary == nullptr) return Status::invalid_argument;
  const Span<const Sample> test = dataset.test();
  const Span<const Sample> predicted(test.data(), test.size() + dataset.set_aside().size());  // stored behind it
  return test_for_blunders(final_stage->model, final_stage->base_to_tracker, dataset.train(), predicted,
                           calibration_estimated_mask(result), blunder_test_loss(options), options.blunder_test,
                           workspace, visitor, summary);
}

Status cross_validate(const RobotModel& start, DatasetBase* dataset, const CalibrationOptions& options,
                      std::size_t folds, CalibrationWorkspaceBase* workspace, CalibrationResult* scratch,
                      CrossValidationResult* cv, CalibrationObserver* observer) {
  if (scratch == nullptr || cv == nullptr) return Status::invalid_argument;
  cv->~CrossValidationResult();
  new (cv) CrossValidationResult();
  Status status = Status::ok;
  std::size_t aside_count = 0;
  CalibrationOptions fold_options = fitted_frames(options);
  if (!options.keep_outliers ||
      detects_controller_frames(options)) {  // blunders and frames, found once on the whole set
    status = calibrate(start, dataset, options, workspace, scratch, observer);
    if (status != Status::ok) return cv->status = status;
    aside_count = scratch->outlier_count;  // 0 with keep_outliers
    fold_options = options_with_chosen_frames(options, *scratch);
  } else if (dataset == nullptr || workspace == nullptr || !known(options) || !compliance_usable(start, options)) {
    return cv->status = Status::invalid_argument;
  }
  std::uint32_t aside[kMaxCalibrationOutliers] = {};
  for (std::size_t i = 0; i < aside_count; ++i) aside[i] = scratch->outliers[i].index;
  const Span<const std::uint32_t> aside_span(aside, aside_count);
  dataset->set_aside(aside_span);
  const std::size_t n = dataset->size();
  const std::size_t poses = dataset->pose_count();  // folds hold out whole poses
  const std::size_t k = folds == 0 ? poses : folds;
  if (k < 2 || k > poses || k > kMaxCrossValidationFolds) return cv->status = Status::invalid_argument;
  double abs_sum_m = 0.0;
  double baseline_sum_m = 0.0;
  for (std::size_t f = 0; f < k; ++f) {
    CalibrationResult& r = reset(scratch);
    dataset->set_aside(aside_span);
    status = dataset->split_fold(f, k, options.seed);
    if (status == Status::ok) status = run_split(start, dataset, fold_options, workspace, &r, observer);
    if (status != Status::ok) return cv->status = status;
    CrossValidationFold& fold = cv->folds[f];
    fold.train_count = r.train_count;
    const CalibrationStage& final_stage = r.stages[r.stage_count - 1];  // a method runs one stage at least
    fold.train = final_stage.train;
    fold.test = final_stage.test;
    fold.baseline_test = r.baseline.test;
    const double mae_m = fold.test.mae(ErrorAxis::norm_3d);
    abs_sum_m += mae_m * static_cast<double>(fold.test.count);
    baseline_sum_m += fold.baseline_test.mae(ErrorAxis::norm_3d) * static_cast<double>(fold.baseline_test.count);
    cv->fold_mae_3d_mean_m += mae_m / static_cast<double>(k);
    cv->fold_mae_3d_max_m = std::fmax(cv->fold_mae_3d_max_m, mae_m);
  }
  cv->fold_count = k;
  cv->sample_count = n;
  cv->mae_3d_m = abs_sum_m / static_cast<double>(n);
  cv->baseline_mae_3d_m = baseline_sum_m / static_cast<double>(n);
  cv->status = Status::ok;
  return Status::ok;
}

}  // namespace hivecal
