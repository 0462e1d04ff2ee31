// What a calibration job returns (calibration.hpp, the job's one entry): the baseline, each
// stage's fit and errors, the joint terms' admission (docs/compliance.md), the blunders set
// aside (docs/robust.md) and the test of the controller's frames.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/core/capacity.hpp"
#include "hivecal/core/span.hpp"
#include "hivecal/core/status.hpp"
#include "hivecal/core/types.hpp"
#include "hivecal/job/calibration_options.hpp"
#include "hivecal/job/joint_term_families.hpp"
#include "hivecal/model/full_params.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/model/metrics.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/solve/reliability.hpp"

namespace hivecal {

/// The test of CalibrationOptions::detect_controller_frames. The controller's frames (the base
/// the identity, the tool points the start model's; joint 1 takes the base's z and rotation
/// about z) are kept when the job's final fit with them explains the data to the measurement
/// noise: its residual sigma within the chi-square bound of that noise at
/// kControllerFramesAlpha. A fit that explains the data to the noise with fewer parameters is
/// the better predictor; the fitted frames' smaller residual is then noise fitted (on 12 poses
/// of a UR5e pendant export it is down to 0.55x the noise). A tracker's points (a tool guessed
/// to a millimetre, a base registered through the nominal model) fit the controller's frames
/// far above the noise and stay fitted.
struct ControllerFramesTest {
  bool tested = false;            ///< the fitted base was within the gate and the known frames' run was made [-]
  bool adopted = false;           ///< the result is the fit with the controller's frames [-]
  double residual_sigma_m = 0.0;  ///< residual sigma per axis of the fit with the controller's frames [m]
  double noise_sigma_m = 0.0;     ///< the measurement noise per axis it is held against (measurement_sigma_m) [m]
  double critical_sigma_m = 0.0;  ///< the largest residual sigma that noise explains at kControllerFramesAlpha [m]
  /// Why the known frames' fit could not be tested although the base was within the gate:
  /// invalid_argument (it set aside more samples as blunders than the fitted frames: it
  /// explains the data only without them), too_few_samples
  /// (no residual degree of freedom), else the status its run failed with; ok when it was.
  Status status = Status::ok;
};

/// The start geometry, before any solver.
struct CalibrationBaseline {
  RobotModel model;                ///< the start geometry with its tool point fitted (when tool_fitted)
  RigidTransform base_to_tracker;  ///< its base fitted on the training samples
  bool tool_fitted =
      false;         ///< the tool point was fitted with the base (LM, nominal joints); false: base only (< 4 samples)
  ErrorStats train;  ///< errors on the training samples [m]
  ErrorStats test;   ///< errors on the test samples (count 0 without a test split) [m]
};

/// How many standard errors the mean improvement on left-out poses must exceed for a
/// small set's added joint terms to stay (JointTermHoldout; one-sided, about 2.5 % by chance) [-].
inline constexpr double kHoldoutImprovementT = 2.0;

/// A joint-term stage's added terms checked on poses the fit did not see (training sets of at
/// most kJointTermHoldoutMaxSamples samples): each training pose (its samples of every target)
/// is left out in turn and predicted by two fits of the others, with the terms the significance
/// test kept and without the stage's added terms. The terms stay only if they predict clearly
/// better: the mean of the poses' improvements exceeds kHoldoutImprovementT standard errors.
struct JointTermHoldout {
  bool checked = false;           ///< the check ran (a small set, and the significance test kept an added term)
  std::size_t poses = 0;          ///< poses left out and predicted [-]
  double with_terms_mae_m = 0.0;  ///< mean over the left-out poses of their 3-D error, fitted with the kept terms [m]
  double without_terms_mae_m = 0.0;  ///< the same, fitted without the stage's added terms [m]
  double improvement_se_m = 0.0;     ///< standard error of without_terms_mae_m - with_terms_mae_m over the poses [m]
  bool passed = false;  ///< every fit finished and the improvement exceeds kHoldoutImprovementT improvement_se_m
};

/// A blocked fold holds out the training poses at one end of one joint's range: this share of
/// them, the lowest or the highest readings of that joint [-].
inline constexpr double kBlockedFoldShare = 0.2;

/// A joint-term stage's added terms on poses beyond the training poses' joint ranges (blocked
/// folds, docs/compliance.md): for each joint, its lowest and its highest kBlockedFoldShare of
/// the training poses are held out in turn and predicted by the fit of the others (one
/// Gauss-Newton step from the stage's fit), with the stage's terms and without the added ones.
/// A joint whose ends its own added terms predict worse loses them; the stage keeps the previous
/// fit when, over every joint's ends, the terms predict worse than without them.
struct BlockedFoldCheck {
  bool checked = false;  ///< the stage kept an added term, and the folds were predicted
  /// Mean 3-D error of joint j's two end folds, each predicted by the fit of the others with the
  /// stage's terms [m] (0 when not checked).
  double with_terms_mae_m[kMaxJoints] = {};
  double without_terms_mae_m[kMaxJoints] = {};  ///< the same without the added terms [m]
  double with_all_mae_m = 0.0;                  ///< over every joint's ends, with the terms [m]
  double without_all_mae_m = 0.0;               ///< the same without them [m]
  /// Harmonics not admitted because the training poses turn their joint through less than
  /// kHarmonicMinPeriodShare of their period.
  ParamMask coverage_rejected = 0;
  ParamMask fold_rejected = 0;  ///< added terms of joints whose end folds they predicted worse
  bool passed = true;           ///< over every joint's ends, the kept terms predict no worse
};

/// A fit's held-out errors on the blocked folds (BlockedFoldCheck), each joint's two ends. No
/// member initializers (a workspace holds one: its constructor stays small in flash): made
/// zero by value-initialization, `BlockedFoldErrors{}`.
struct BlockedFoldErrors {
  double sum_m[kMaxJoints][2];       ///< sum of the 3-D errors of the fold's samples [m]
  double squares_m2[kMaxJoints][2];  ///< sum of their squares [m^2]
  std::size_t count[kMaxJoints][2];  ///< samples of the fold [-]
  bool solved[kMaxJoints][2];        ///< the fit of the others could be made (a positive definite system)
};

/// What one solver stage produced.
struct CalibrationStage {
  CalibrationSolver solver = CalibrationSolver::lm;  ///< which solver ran
  bool refines_previous = false;                     ///< LM started from the previous stage's geometry and base
  bool compliance = false;  ///< LM estimated the model's joint terms too ("LM+compliance", "LM+harmonics", ...)
  /// A joint-term stage none of whose added terms passed the significance test (or, on a small
  /// set, whose kept terms failed `holdout`): the stage holds
  /// the previous fit (the rigid one, or LM+compliance before LM+compliance+harmonics) with the
  /// new terms at their start values, and `lm` its details.
  bool rigid_kept = false;
  JointTermHoldout
      holdout;             ///< a joint-term stage on a small set: its terms on left-out poses (rigid_kept when failed)
  BlockedFoldCheck folds;  ///< a joint-term stage: its terms beyond the training poses' joint ranges
  CalibrationParams params = CalibrationParams::paper;  ///< parameters it could move
  Status status = Status::ok;                           ///< ok, or not_converged (LM's last point kept)
  RobotModel model;                                     ///< calibrated geometry
  RigidTransform base_to_tracker;                       ///< its base -> tracker transform
  std::uint64_t evaluations = 0;                        ///< cost evaluations (LM: iterations) [-]
  std::size_t iterations = 0;                           ///< cycles / iterations run [-]
  double best_cost_m =
      0.0;  ///< ABC/GSA: best MAE on the samples it searched on, as the cost computed it; LM: final RMS [m]
  std::size_t searched_samples =
      0;                       ///< ABC/GSA: training samples the cost held (a spanning subset in a hybrid); LM: 0 [-]
  ErrorStats train;            ///< errors on the training samples [m]
  ErrorStats test;             ///< errors on the test samples [m]
  Span<const double> trace_m;  ///< best cost (ABC/GSA: MAE, LM: RMS) per iteration [m]; views the workspace
  ParamMask estimated = 0;     ///< LM: the parameters it estimated (its kept set)
  double residual_sigma_m = 0.0;  ///< LM: its residual sigma per axis (LmResult::residual_sigma_m) [m]
  /// LM: the tolerances its prior held (LmResult::prior_tolerances); zero: no prior [m], [rad]
  LmPriorTolerances prior_tolerances;
};

/// Stages a job runs at most ('all': GSA, ABC, LM, then LM+compliance when enabled, and
/// LM+compliance+harmonics after it when the terms hold both families: a capacity that holds
/// the harmonics, core/capacity.hpp).
inline constexpr std::size_t kMaxCalibrationStages = kMaxJointTerms >= 4 + 2 * kSixJoints ? 5 : 4;

/// The steps of a job, in order (CalibrationResult::step is the last one reached).
enum class CalibrationStep : std::uint8_t { input, split, baseline, gsa, abc, lm, done };

/// A sample the job set aside as a blunder.
struct CalibrationOutlier {
  std::uint32_t index = 0;  ///< its Sample::index (order of DatasetBase::add) [-]
  double residual_m = 0.0;  ///< |predicted - measured| under the final calibration [m]
  double w = 0.0;           ///< its pose's normalised residual against the fit without it (UnitTest::w) [-]
  double critical_w = 0.0;  ///< the threshold it exceeded [-]
};

/// What the blunder search concluded.
enum class BlunderVerdict : std::uint8_t {
  not_searched,  ///< keep_outliers, or the fit left nothing to test
  clean,         ///< no pose failed the test
  removed,       ///< the poses in `outliers` failed it and were set aside
  model_error,  ///< more than max_blunder_share of the poses failed: the model, not the data, is wrong; none removed by
                ///< the test
  list_full,    ///< more blunders than kMaxCalibrationOutliers: the largest are set aside
  /// a pose fails the test while fitted and passes when left out (the split moves with it),
  /// run after run: kept, with those in `outliers` (failed both ways) set aside
  at_threshold,
  /// more than max_blunder_share of the split's test poses fail as predictions: the fit does not
  /// carry to poses it did not see (too few poses, unmodelled effects); none of them set aside
  prediction_error,
};

/// Lower-case name of a verdict ("not_searched", "clean", "removed", "model_error", "list_full",
/// "at_threshold", "prediction_error").
const char* blunder_verdict_name(BlunderVerdict verdict);

/// Blunders a job sets aside at most; a larger share of a set is not a blunder problem [-].
inline constexpr std::size_t kMaxCalibrationOutliers = 64;

/// One list of the blunder search (the set aside, the last test's flags): kept in the
/// workspace beside the arena, as it lives across the job's runs.
struct CalibrationOutlierList {
  CalibrationOutlier items[kMaxCalibrationOutliers];    ///< flagged samples, by index once complete
  std::uint32_t indices[kMaxCalibrationOutliers] = {};  ///< their Sample::index, increasing [-]
  std::size_t count = 0;                                ///< entries used [-]
  std::size_t limit = kMaxCalibrationOutliers;          ///< entries allowed (fewer than half the set) [-]
};

/// Short name of a stage ("ABC", "GSA", "LM", "ABC+LM", "GSA+LM", "LM+compliance",
/// "LM+harmonics", "LM+compliance+harmonics" after the joint terms of its model; the
/// previous stage's name is taken from `refines_previous` and `previous`).
const char* calibration_stage_name(const CalibrationStage& stage, const CalibrationStage* previous);
/// The level full-model parameter `index` of `model` must clear in the significance test of a
/// stage at level `significance_t` (CalibrationResult::significance_t): that level for the
/// geometry; at least `compliance_t` (CalibrationCompliance::significance_t) for a gravity
/// term; for a harmonic, the level raised for the model's harmonics as a family
/// (kHarmonicFamilyAlpha, Student's t with the fit's `dof` residual degrees of freedom; infinite
/// below 1: a fit without redundancy keeps no harmonic) [-].
double parameter_significance_level(const RobotModel& model, int index, double significance_t, double compliance_t,
                                    int dof);
/// Name of a solver ("ABC", "GSA", "LM").
const char* calibration_solver_name(CalibrationSolver solver);
/// Name of a step ("input", "split", "baseline", "gsa", "abc", "lm", "done").
const char* calibration_step_name(CalibrationStep step);

/// Everything a job returns (~6 KB with the LmResult and the blunder list: static storage on a small target).
struct CalibrationResult {
  CalibrationResult();                       ///< nothing run yet (out of line: the firmware's flash holds one copy)
  Status status = Status::invalid_argument;  ///< ok, or why the job stopped at `step`
  CalibrationStep step = CalibrationStep::input;  ///< done on success, else the step that failed
  std::size_t train_count = 0;                    ///< training samples [-]
  std::size_t test_count = 0;                     ///< test samples [-]
  std::size_t train_points =
      0;  ///< distinct points (pose x target) of the training samples, <= kDistinctPointLimit [-]
  CalibrationBaseline baseline;                    ///< the start geometry's fit
  CalibrationStage stages[kMaxCalibrationStages];  ///< the stages run, in order
  std::size_t stage_count = 0;                     ///< entries of `stages` used [-]
  bool has_lm = false;                             ///< an LM stage ran: `lm` is meaningful
  LmResult lm;  ///< the last LM stage's details (LM+compliance's when it ran): identifiability, sigma, rms, termination
  ParamMask lm_pruned_mask = 0;  ///< parameters LM fixed at their start values as not significant (significance_t)
  double significance_t = 0.0;   ///< the significance level LM used (options', or the one chosen) [-]
  bool geometry_tested = true;  ///< the significance test covered the geometry (a small set, or significance_every_set)
  std::size_t significance_poses = 0;   ///< distinct_configurations() of the final LM fit's samples [-]
  std::size_t significance_params = 0;  ///< rigid parameters its first attempt estimated [-]
  CalibrationOutlier outliers[kMaxCalibrationOutliers];  ///< samples set aside, by increasing index
  std::size_t outlier_count = 0;                         ///< entries of `outliers` used [-]
  std::size_t outlier_rounds = 0;  ///< times the job ran until the set aside was stable (0: keep_outliers) [-]
  BlunderVerdict blunder_verdict = BlunderVerdict::not_searched;  ///< what the search concluded
  BlunderTestSummary
      blunder_test;               ///< the last w-test of the final fit on its training poses (sigma, dof, uncontrolled)
  std::size_t blunder_limit = 0;  ///< training poses the w-test may remove (max_blunder_share) [-]
  std::size_t test_blunder_limit = 0;  ///< test poses that may fail as predictions (max_blunder_share) [-]
  /// The tracker's scatter over repeated readings of the kept samples (a blunder set aside is
  /// not noise); groups == 0 when the input repeats no reading.
  RepeatedReadingNoise reading_noise;
  /// The test of the controller's frames (CalibrationOptions::detect_controller_frames); when
  /// adopted, the result is that of the options with base_known, tool_known and LM only.
  ControllerFramesTest frames_test;

  /// The samples set aside, by increasing index.
  Span<const CalibrationOutlier> outlier_list() const {
    return Span<const CalibrationOutlier>(outliers, outlier_count);
  }

  /// The stages run, in order.
  Span<const CalibrationStage> stage_list() const { return Span<const CalibrationStage>(stages, stage_count); }
  /// The last stage (the job's answer); null when none ran.
  const CalibrationStage* final_stage() const { return stage_count == 0 ? nullptr : &stages[stage_count - 1]; }
  /// Name of stage k < stage_count (see calibration_stage_name).
  const char* stage_name(std::size_t k) const {
    return calibration_stage_name(stages[k], k == 0 ? nullptr : &stages[k - 1]);
  }
};

}  // namespace hivecal
