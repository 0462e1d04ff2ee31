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
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <new>

#include "hivecal/core/span.hpp"
#include "hivecal/core/status.hpp"
#include "hivecal/core/trace.hpp"
#include "hivecal/core/types.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/model/metrics.hpp"
#include "hivecal/solve/abc.hpp"
#include "hivecal/solve/gsa.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/solve/objective.hpp"
#include "hivecal/solve/paper6_cost.hpp"
#include "hivecal/solve/population_stage.hpp"
#include "hivecal/solve/reliability.hpp"

namespace hivecal {

/// Which solvers run, in order.
enum class CalibrationMethod : std::uint8_t {
  lm,      ///< Levenberg-Marquardt from the start geometry
  abc,     ///< ABC on the link lengths (for UR the paper's six)
  gsa,     ///< GSA on the link lengths (for UR the paper's six)
  abc_lm,  ///< ABC, then LM from its geometry and base (the hybrid)
  gsa_lm,  ///< GSA, then LM from its geometry and base
  all,     ///< the paper's Table 1: GSA, ABC and LM, each from the start geometry
};

/// What LM may move (ABC and GSA always search the link lengths: link_length_set(start)).
enum class CalibrationParams : std::uint8_t {
  full,   ///< every parameter the data identifies (LmParamSet::full)
  paper,  ///< the link lengths (for UR the paper's six) and the base (LmParamSet::link_lengths)
};

/// One solver of a stage.
enum class CalibrationSolver : std::uint8_t { abc, gsa, lm };

/// Joint compliance in the job (docs/compliance.md); off by default.
struct CalibrationCompliance {
  /// After the rigid LM stage, one more LM stage ("LM+compliance") from its geometry and base
  /// that estimates the compliance terms with the geometry. Needs a method with LM.
  bool enabled = false;
  /// The terms, their load kind, the gravity direction, the masses and the start
  /// coefficients; term_count 0: default_compliance_terms of the start geometry for `load`
  /// and `gravity_direction`.
  ComplianceModel model;
  /// Level of the significance test for the compliance terms, when the test is on: a term is
  /// a new model term, not a correction to a known one, so it must clear this (and at least
  /// significance_t) to stay; below it the term is fixed at its start value. The harmonics,
  /// many generic terms, clear a level raised so that an arm without harmonics keeps one by
  /// chance at most kHarmonicFamilyAlpha of the time (24 terms: 3.53) [-].
  double significance_t = 3.0;
};

/// Chance that a stage keeps any of its harmonic terms on an arm without harmonics
/// (Bonferroni over the terms; CalibrationCompliance::significance_t) [-].
inline constexpr double kHarmonicFamilyAlpha = 0.01;

/// Default level of LM's significance test: a parameter whose change is below 2 sigma is fixed [-].
inline constexpr double kDefaultSignificance = 2.0;
/// Unless CalibrationOptions::significance_every_set, LM's significance test covers the geometry
/// (and the base) of a small set only: fewer training poses (distinct_configurations) than this
/// many per rigid parameter the fit estimates. A larger set estimates every identifiable one, as
/// a least-squares fit does. Measured on a real UR10 (random parts of 12-1,000 poses, 23
/// parameters, docs/robust.md): at 0.5 poses per parameter the test is what makes the fit
/// predict (14 % better), at 0.9-1.3 the two are within 3 % either way, from 1.5 on the test
/// costs 0.2-2.2 % of held-out error [-].
inline constexpr double kSignificancePosesPerParam = 1.5;
/// Default size of the spanning subset a hybrid's population stage searches on [samples]:
/// the stage only starts LM, and 128 samples are ~40 equations per searched unknown (six
/// link lengths, the base fitted in closed form); the stage's cost stops growing with the set.
/// Against 256 the stage costs 0.055 s instead of 0.085 s and its own MAE is 1-2 % higher;
/// LM ends at the same accuracy (docs/solvers-abc-gsa.md).
inline constexpr std::size_t kDefaultPopulationSubset = 128;
/// Largest spanning subset a workspace holds room for (CalibrationWorkspace::SubsetCapacity's
/// default, the size-erased view's room; 4 B each) [samples].
inline constexpr std::size_t kMaxPopulationSubset = 256;
/// Largest training set on which a negative significance_t chooses the level by leaving one pose out at a time [-].
inline constexpr std::size_t kAutoSignificanceMaxSamples = 64;
/// Largest training set on which a joint-term stage's kept terms are checked on left-out poses
/// (JointTermHoldout): where the significance test, which trusts the residuals' sigma, is weakest,
/// and where a refit per pose is cheap [-].
inline constexpr std::size_t kJointTermHoldoutMaxSamples = kAutoSignificanceMaxSamples;

/// Default manufacturing tolerances of the start model in the job's LM fits (the nominal model
/// as a prior, docs/solver-lm.md): 1 mm per DH length, 5 mrad per DH angle, 20 mm per
/// coordinate of the given tool point [m], [rad].
inline constexpr LmPriorTolerances kDefaultPriorTolerances{1e-3, 5e-3, 0.02};

/// Settings of one job; the defaults are the command-line tool's.
struct CalibrationOptions {
  CalibrationMethod method = CalibrationMethod::abc_lm;  ///< solvers and their order
  CalibrationParams params = CalibrationParams::full;    ///< what LM may move
  double train_fraction = kDefaultTrainFraction;  ///< share of samples for training, in (0, 1]; 1: no test samples [-]
  std::uint64_t seed = 1;                         ///< seed of the split and of ABC/GSA [-]
  bool robust = false;                            ///< Huber loss in LM (sets lm.loss)
  std::size_t abc_food_sources = 150;             ///< ABC SN, <= the workspace's population capacity [-]
  std::size_t abc_cycles = 300;                   ///< ABC MCN [-]
  std::size_t gsa_agents = 150;                   ///< GSA N, <= the workspace's population capacity [-]
  std::size_t gsa_iterations = 200;               ///< GSA t_max [-]
  double paper6_half_width_m = kPaper6DefaultHalfWidth_m;  ///< ABC/GSA box: start lengths +/- this [m]
  /// Hybrids (abc+lm, gsa+lm): the population stage searches on at most this many training
  /// samples, chosen to span the poses (spanning_subset; at most the workspace's
  /// subset capacity), and LM refines on every sample; 0: on every sample. The paper's
  /// methods (abc, gsa, all) always search on every sample [-].
  std::size_t population_subset = kDefaultPopulationSubset;
  LmOptions lm;  ///< LM settings; `params` and `robust` override its params and loss
  double significance_t =
      kDefaultSignificance;  ///< LM fixes, one at a time, estimated parameters whose change is below t sigma (0: off; <
                             ///< 0: chosen by leaving one pose out at a time on small sets) [-]
  /// true: the significance test covers the geometry on every set; false: only on a small set
  /// (kSignificancePosesPerParam), a larger one fixes joint terms only [-].
  bool significance_every_set = false;
  bool keep_outliers = false;  ///< true: no blunder search, every sample is used
  BlunderTestOptions
      blunder_test;  ///< the w-test of the calibration's poses (significance, tracker sigma, redundancy floor)
  /// Largest share of the training poses the w-test removes (at least one); more would go when
  /// the model, not the data, is wrong (residuals of unmodelled effects): then none is removed
  /// and the result says so (BlunderVerdict::model_error). The same share of the split's test
  /// poses failing as predictions: none of them is set aside (BlunderVerdict::prediction_error) [-].
  double max_blunder_share = 0.05;
  double outlier_k =
      6.0;  ///< the consensus screen sets a sample aside when |r| > max(k sigma_robust, screen_floor_m) [-]
  double screen_floor_m = 0.01;        ///< smallest residual set aside by the start geometry's consensus screen [m]
  std::size_t consensus_trials = 200;  ///< point triples tried by the consensus (LMedS) screen [-]
  CalibrationCompliance compliance;    ///< joint compliance stage (off by default)
  /// Every LM fit holds the start model (its DH and the given tool point) as a prior with these
  /// tolerances, so that what the data do not determine stays at nominal; all 0: off, plain
  /// least squares [m], [rad].
  LmPriorTolerances prior = kDefaultPriorTolerances;
  /// The base -> tracker transform is known and not estimated: the points were measured in
  /// the robot's own frame (a teach pendant's or controller's TCP readings: the identity), or
  /// the base was calibrated before. Joint 1's parameters, which a fitted base absorbs, become
  /// estimable. Only with CalibrationMethod::lm (ABC/GSA fit their own base) [-].
  bool base_known = false;
  RigidTransform known_base_to_tracker;  ///< with base_known: the fixed transform [m, rad]
  /// Every target's tool point is known and not estimated (the start model's): a controller's
  /// TCP readings are FK(q) * its configured TCP offset, exactly. Only with
  /// CalibrationMethod::lm [-].
  bool tool_known = false;
  /// Whether the points may be a controller's own TCP readings (a pendant export, RTDE's
  /// actual_TCP_pose) rather than a tracker's: the job fits the frames, and when the fitted
  /// base is near the identity (kControllerBaseGate_m, kControllerBaseGate_rad) it runs again
  /// with the controller's frames, base_known (the identity) and tool_known, LM only, and keeps
  /// that fit when it explains the data to the measurement noise (ControllerFramesTest). No
  /// effect with base_known or tool_known set, or a method other than lm, abc_lm and gsa_lm
  /// (`all` compares the paper's three stages on the same frames) [-].
  bool detect_controller_frames = false;
  /// The measurement noise per axis of a point, for detect_controller_frames: the tracker's
  /// stated with the joints' reading noise through the arm (0: blunder_test.tracker_sigma_m);
  /// repeated readings in the input, when they scatter, take its place [m].
  double measurement_sigma_m = 0.0;
};

/// A fitted base this close to the identity makes the job test the controller's frames
/// (detect_controller_frames): a tracker's frame is never within it, and a controller's base is
/// the identity up to joint 1's calibration, a fraction of a millimetre and a milliradian [m].
inline constexpr double kControllerBaseGate_m = 0.01;
/// The same gate on the base's rotation angle [rad].
inline constexpr double kControllerBaseGate_rad = 0.01;

/// Level at which the controller's frames are rejected: their fit's residual sum against the
/// measurement noise's chi-square (the blunder test's level: a controller's readings are the
/// simpler hypothesis, given up only on strong evidence) [-].
inline constexpr double kControllerFramesAlpha = 0.001;

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

/// Lower-case name of a method as the command line spells it ("abc+lm", "all", ...).
const char* calibration_method_name(CalibrationMethod method);

/// The names calibration_method_from_name accepts, for messages and help:
/// "abc+lm, gsa+lm, lm, abc, gsa, all" (the default first).
const char* calibration_method_names();

/// The method a name spells (calibration_method_name's inverse). Errors: invalid_argument
/// (null or unknown name; *method unchanged).
Status calibration_method_from_name(const char* name, CalibrationMethod* method);

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

/// A harmonic is admitted only when the training poses turn its joint through at least this
/// share of its period (2 pi / order): over less, it is a polynomial the geometry holds too, and
/// nothing ties it down beyond the poses' range [-].
inline constexpr double kHarmonicMinPeriodShare = 0.75;
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

/// Scratch of the blunder search: one predicted point and one residual per sample.
struct ResidualScratch {
  Span<Vec3> predicted_m;   ///< tool points of the start geometry in the base frame [m]
  Span<double> residual_m;  ///< residual norms [m]
};

/// Capacity-erased workspace: the phases of a job (population cost + solver, LM workspace)
/// are built one at a time in one arena, and the stage traces outlive them.
class CalibrationWorkspaceBase {
 public:
  CalibrationWorkspaceBase(const CalibrationWorkspaceBase&) = delete;
  CalibrationWorkspaceBase& operator=(const CalibrationWorkspaceBase&) = delete;

  /// The objects of a population phase.
  struct PopulationPhase {
    Paper6CostBase* cost = nullptr;  ///< paper-6 cost with room for the training samples
    AbcSolverBase* abc = nullptr;    ///< set by open_abc()
    GsaSolverBase* gsa = nullptr;    ///< set by open_gsa()
    /// The GSA stage (calibrate_paper6_gsa), set with `gsa`: a workspace without GSA never
    /// references its code (the firmware's flash).
    decltype(&calibrate_paper6_gsa) run_gsa = nullptr;
  };
  /// Ends any open phase, builds a cost and an ABC solver in the arena.
  virtual PopulationPhase open_abc() = 0;
  /// Ends any open phase, builds a cost and a GSA solver in the arena (both null: the workspace
  /// has no room for GSA).
  virtual PopulationPhase open_gsa() = 0;
  /// Ends any open phase, builds an LM workspace (joint trig storage attached if the type has it).
  virtual LmWorkspace* open_lm() = 0;
  /// An LM workspace with a result of its own.
  struct LmScratch {
    LmWorkspace* lm = nullptr;   ///< as open_lm()'s
    LmResult* result = nullptr;  ///< where a fit that is not the job's goes (the blunder search's refits)
  };
  /// Ends any open phase, builds open_lm()'s workspace and a result beside it in the arena: the
  /// job's result keeps its final fit.
  virtual LmScratch open_lm_scratch() = 0;
  /// Ends the open phase (its objects are destroyed).
  virtual void close() = 0;
  /// The trace of stage `index` (< kMaxCalibrationStages).
  virtual TraceBase& trace(std::size_t index) = 0;
  /// Ends any open phase, builds the blunder search's scratch in the arena: one predicted
  /// point and one residual per sample, for up to the workspace's sample count.
  virtual ResidualScratch open_residuals() = 0;
  /// The blunder search's lists: 0 the set aside, 1 the last test's.
  virtual CalibrationOutlierList& outlier_list(std::size_t which) = 0;
  /// Ends any open phase, builds the w-test's scratch in the arena.
  virtual ReliabilityWorkspace* open_reliability() = 0;
  /// Room for the positions of a hybrid's spanning subset (empty: none, every sample is searched).
  virtual Span<std::uint32_t> subset_room() = 0;
  /// Where the w-test's removals are undone from: (position, end of the fitted part) per removed pose.
  std::uint32_t (&snoop_moves())[kMaxCalibrationOutliers][2] { return snoop_moves_; }
  /// Where an LM stage keeps the geometry it starts from while it reruns (dropped or not
  /// significant parameters put back): in the workspace, not on the stack under LM (a model
  /// with its compliance is 584 B, and the firmware's stack peak is inside LM).
  RobotModel& lm_start() { return lm_start_; }
  /// Where a joint-term stage keeps the previous fit's errors on the blocked folds while it fits
  /// again (BlockedFoldCheck): not on the stack under LM.
  BlockedFoldErrors& previous_fold_errors() { return previous_fold_errors_; }

 protected:
  CalibrationWorkspaceBase() = default;
  ~CalibrationWorkspaceBase() = default;

 private:
  RobotModel lm_start_;
  BlockedFoldErrors previous_fold_errors_;
  std::uint32_t snoop_moves_[kMaxCalibrationOutliers][2] = {};
};

namespace detail {
/// Joint trig storage for LM, or none (Samples = 0).
template <std::size_t Samples>
struct JointTrigStorage {
  JointTrig values[Samples];
  Span<JointTrig> view() { return Span<JointTrig>(values, Samples); }
};
template <>
struct JointTrigStorage<0> {
  Span<JointTrig> view() { return Span<JointTrig>(); }
};
/// Target blocks for LM's normal equations (several targets), or none (Blocks = 0).
template <std::size_t Blocks>
struct TargetBlockStorage {
  TargetBlock values[Blocks];
  Span<TargetBlock> view() { return Span<TargetBlock>(values, Blocks); }
};
template <>
struct TargetBlockStorage<0> {
  Span<TargetBlock> view() { return Span<TargetBlock>(); }
};
template <std::size_t A, std::size_t B>
inline constexpr std::size_t max_of = A > B ? A : B;
/// Room for a spanning subset's positions, or none (Count = 0).
/// GSA's phase: the cost and a solver of `Population` agents, or nothing (Population = 0).
template <typename Cost, std::size_t Population, std::size_t Lengths>
struct GsaPhaseStorage {
  Cost cost;
  GsaSolver<Population, Lengths> solver;
};
template <typename Cost, std::size_t Lengths>
struct GsaPhaseStorage<Cost, 0, Lengths> {};
template <std::size_t Count>
struct SubsetStorage {
  std::uint32_t values[Count];
  Span<std::uint32_t> view() { return Span<std::uint32_t>(values, Count); }
};
template <>
struct SubsetStorage<0> {
  Span<std::uint32_t> view() { return Span<std::uint32_t>(); }
};
}  // namespace detail

/// A workspace for jobs on up to `Samples` training samples and up to `MaxLinkLengths` link
/// lengths (6: UR arms, the firmware; kMaxLinkLengths: any arm): paper-6 cost with `CostScalar`
/// terms (double: exact; float: half the memory, the firmware's choice), ABC and GSA with up to
/// `Population` members, traces of `TraceCapacity` iterations per stage, and joint trig
/// storage for LM when `JointTrigSamples` > 0 (faster, same bits), and LM's blocks for the
/// tool points of up to `MaxTargets` reflectors (1: one reflector only, 3.6 kB less; the
/// firmware's choice), and room for a hybrid's spanning subset of `SubsetCapacity` samples
/// (4 B each; 0: a hybrid's population stage searches on every sample, as the paper's methods
/// do; by default none for up to kDefaultPopulationSubset samples, else room for up to
/// kMaxPopulationSubset), and GSA with up to `GsaPopulation` agents (0: no GSA phase, a job with GSA ends with
/// population_out_of_range; the firmware's choice, 7.2 kB less). Big: give it static storage.
template <std::size_t Samples, typename CostScalar = double, std::size_t Population = 150,
          std::size_t TraceCapacity = 300, std::size_t JointTrigSamples = 0,
          std::size_t MaxLinkLengths = kPaper6Dimension, std::size_t MaxTargets = kMaxTargets,
          std::size_t SubsetCapacity = (Samples <= kDefaultPopulationSubset ? 0
                                        : Samples < kMaxPopulationSubset    ? Samples
                                                                            : kMaxPopulationSubset),
          std::size_t GsaPopulation = Population>
class CalibrationWorkspace final : public CalibrationWorkspaceBase {
 public:
  using Cost = Paper6Cost<Samples, CostScalar, MaxLinkLengths>;  ///< the population stages' cost
  /// The ABC phase's objects.
  struct AbcPhase {
    Cost cost;
    AbcSolver<Population, MaxLinkLengths> solver;
  };
  /// The GSA phase's objects (none when GsaPopulation is 0).
  using GsaPhase = detail::GsaPhaseStorage<Cost, GsaPopulation, MaxLinkLengths>;
  /// The LM phase's objects.
  struct LmPhase {
    LmWorkspace lm;
    detail::JointTrigStorage<JointTrigSamples> joint_trig;
    detail::TargetBlockStorage<2 * (MaxTargets - 1)> target_blocks;
    LmResult scratch_result;  ///< open_lm_scratch()'s (4 kB on the firmware: the ABC phase is larger)
  };
  /// The blunder search's scratch.
  struct ResidualPhase {
    Vec3 predicted_m[Samples];
    double residual_m[Samples];
  };
  /// Bytes of the arena: the largest phase.
  static constexpr std::size_t kArenaBytes =
      detail::max_of<detail::max_of<detail::max_of<sizeof(AbcPhase), sizeof(GsaPhase)>, sizeof(LmPhase)>,
                     detail::max_of<sizeof(ResidualPhase), sizeof(ReliabilityWorkspace)>>;

  CalibrationWorkspace() = default;
  ~CalibrationWorkspace() { close(); }

  PopulationPhase open_abc() override {
    close();
    abc_ = new (arena_) AbcPhase();
    return PopulationPhase{&abc_->cost, &abc_->solver, nullptr};
  }
  PopulationPhase open_gsa() override {
    close();
    if constexpr (GsaPopulation == 0) {
      return PopulationPhase{};  // no room for GSA
    } else {
      gsa_ = new (arena_) GsaPhase();
      return PopulationPhase{&gsa_->cost, nullptr, &gsa_->solver, &calibrate_paper6_gsa};
    }
  }
  LmWorkspace* open_lm() override {
    close();
    lm_ = new (arena_) LmPhase();
    lm_->lm.joint_trig = lm_->joint_trig.view();
    lm_->lm.target_blocks = lm_->target_blocks.view();
    return &lm_->lm;
  }
  LmScratch open_lm_scratch() override {
    LmWorkspace* lm = open_lm();
    return LmScratch{lm, &lm_->scratch_result};
  }
  ResidualScratch open_residuals() override {
    close();
    residuals_ = new (arena_) ResidualPhase();
    return ResidualScratch{Span<Vec3>(residuals_->predicted_m, Samples), Span<double>(residuals_->residual_m, Samples)};
  }
  ReliabilityWorkspace* open_reliability() override {
    close();
    reliability_ = new (arena_) ReliabilityWorkspace();
    return reliability_;
  }
  void close() override {
    if (reliability_ != nullptr) reliability_->~ReliabilityWorkspace();
    reliability_ = nullptr;
    if (abc_ != nullptr) abc_->~AbcPhase();
    if (gsa_ != nullptr) gsa_->~GsaPhase();
    if (lm_ != nullptr) lm_->~LmPhase();
    if (residuals_ != nullptr) residuals_->~ResidualPhase();
    abc_ = nullptr;
    gsa_ = nullptr;
    lm_ = nullptr;
    residuals_ = nullptr;
  }
  TraceBase& trace(std::size_t index) override { return traces_[index]; }
  CalibrationOutlierList& outlier_list(std::size_t which) override { return outlier_lists_[which]; }
  Span<std::uint32_t> subset_room() override { return subset_.view(); }

 private:
  alignas(alignof(std::max_align_t)) unsigned char arena_[kArenaBytes];
  Trace<TraceCapacity> traces_[kMaxCalibrationStages];
  CalibrationOutlierList outlier_lists_[2];
  detail::SubsetStorage<SubsetCapacity> subset_;
  AbcPhase* abc_ = nullptr;  // the open phase (at most one is set), built in arena_
  GsaPhase* gsa_ = nullptr;
  LmPhase* lm_ = nullptr;
  ResidualPhase* residuals_ = nullptr;
  ReliabilityWorkspace* reliability_ = nullptr;
};

namespace detail {
/// `bytes` rounded up to a multiple of the arena's alignment.
constexpr std::size_t arena_round(std::size_t bytes) {
  return (bytes + alignof(std::max_align_t) - 1) / alignof(std::max_align_t) * alignof(std::max_align_t);
}
/// `count` value-initialised T built one by one at `at` (an array new may add a cookie); the
/// first of them (null when count is 0). `at` must be aligned for T.
template <typename T>
T* construct_array(unsigned char* at, std::size_t count) {
  T* first = nullptr;
  for (std::size_t i = 0; i < count; ++i) {
    T* made = new (at + i * sizeof(T)) T();
    if (i == 0) first = made;
  }
  return first;
}
}  // namespace detail

/// A workspace over the caller's arena for jobs on up to `samples` samples, a count chosen
/// at run time (a host program's: any set that fits in memory; the arena is
/// arena_bytes(samples), allocated where the caller likes). Otherwise the host's choices:
/// exact (double) paper-6 terms for any arm's link lengths, ABC and GSA with up to
/// `Population` members, traces of `TraceCapacity` iterations per stage, joint trig storage for
/// LM, every target, room for a spanning subset. The same bits as CalibrationWorkspace<samples,
/// double, Population, TraceCapacity, samples, kMaxLinkLengths>. Unusable until attach().
template <std::size_t Population = 150, std::size_t TraceCapacity = 300>
class CalibrationWorkspaceView final : public CalibrationWorkspaceBase {
  using Abc = AbcSolver<Population, kMaxLinkLengths>;
  using Gsa = GsaSolver<Population, kMaxLinkLengths>;
  static constexpr std::size_t kTargetBlocks = 2 * (kMaxTargets - 1);
  /// Most samples: every arena size below fits a std::size_t.
  static constexpr std::size_t kMaxSamples = std::size_t{1} << (sizeof(std::size_t) >= 8 ? 32 : 22);

  static constexpr std::size_t cost_values(std::size_t samples) {
    return paper6_storage_values(samples, kMaxLinkLengths);
  }
  static constexpr std::size_t population_bytes(std::size_t samples, std::size_t solver_bytes) {
    return detail::arena_round(solver_bytes) + detail::arena_round(sizeof(Paper6CostView)) +
           cost_values(samples) * sizeof(double);
  }
  static constexpr std::size_t lm_bytes(std::size_t samples) {
    return detail::arena_round(sizeof(LmWorkspace)) + detail::arena_round(sizeof(TargetBlock) * kTargetBlocks) +
           detail::arena_round(sizeof(LmResult)) + sizeof(JointTrig) * samples;
  }
  static constexpr std::size_t residual_bytes(std::size_t samples) {
    return detail::arena_round(sizeof(Vec3) * samples) + sizeof(double) * samples;
  }

 public:
  /// Bytes of arena a workspace for `samples` samples needs (the largest phase) [B].
  static constexpr std::size_t arena_bytes(std::size_t samples) {
    return std::max(std::max(population_bytes(samples, sizeof(Abc)), population_bytes(samples, sizeof(Gsa))),
                    std::max(std::max(lm_bytes(samples), residual_bytes(samples)), sizeof(ReliabilityWorkspace)));
  }

  CalibrationWorkspaceView() = default;
  ~CalibrationWorkspaceView() { close(); }

  /// Works in `arena` (aligned to std::max_align_t, at least arena_bytes(samples) bytes, to
  /// outlive the workspace or the next attach()) for up to `samples` samples. Errors:
  /// invalid_argument (no samples, too many, arena too small or misaligned; nothing changed).
  Status attach(Span<unsigned char> arena, std::size_t samples) {
    const bool aligned = reinterpret_cast<std::uintptr_t>(arena.data()) % alignof(std::max_align_t) == 0;
    if (samples == 0 || samples > kMaxSamples || !aligned || arena.size() < arena_bytes(samples)) {
      return Status::invalid_argument;
    }
    close();
    arena_ = arena.data();
    samples_ = samples;
    return Status::ok;
  }
  /// Samples the attached arena holds (0: not attached) [-].
  std::size_t samples() const { return samples_; }

  PopulationPhase open_abc() override {
    close();
    if (arena_ == nullptr) return PopulationPhase{};
    abc_ = new (arena_) Abc();
    return PopulationPhase{open_cost(sizeof(Abc)), abc_, nullptr};
  }
  PopulationPhase open_gsa() override {
    close();
    if (arena_ == nullptr) return PopulationPhase{};
    gsa_ = new (arena_) Gsa();
    return PopulationPhase{open_cost(sizeof(Gsa)), nullptr, gsa_, &calibrate_paper6_gsa};
  }
  LmWorkspace* open_lm() override {
    close();
    if (arena_ == nullptr) return nullptr;
    lm_ = new (arena_) LmWorkspace();
    unsigned char* at = arena_ + detail::arena_round(sizeof(LmWorkspace));
    TargetBlock* blocks = detail::construct_array<TargetBlock>(at, kTargetBlocks);
    lm_->target_blocks = Span<TargetBlock>(blocks, kTargetBlocks);
    at += detail::arena_round(sizeof(TargetBlock) * kTargetBlocks);
    lm_result_ = new (at) LmResult();
    at += detail::arena_round(sizeof(LmResult));
    lm_->joint_trig = Span<JointTrig>(detail::construct_array<JointTrig>(at, samples_), samples_);
    return lm_;
  }
  LmScratch open_lm_scratch() override {
    LmWorkspace* lm = open_lm();
    return LmScratch{lm, lm == nullptr ? nullptr : lm_result_};
  }
  ResidualScratch open_residuals() override {
    close();
    if (arena_ == nullptr) return ResidualScratch{};
    Vec3* predicted = detail::construct_array<Vec3>(arena_, samples_);
    double* residual = detail::construct_array<double>(arena_ + detail::arena_round(sizeof(Vec3) * samples_), samples_);
    return ResidualScratch{Span<Vec3>(predicted, samples_), Span<double>(residual, samples_)};
  }
  ReliabilityWorkspace* open_reliability() override {
    close();
    if (arena_ == nullptr) return nullptr;
    reliability_ = new (arena_) ReliabilityWorkspace();
    return reliability_;
  }
  void close() override {
    if (cost_ != nullptr) cost_->~Paper6CostView();
    if (abc_ != nullptr) abc_->~Abc();
    if (gsa_ != nullptr) gsa_->~Gsa();
    if (lm_ != nullptr) lm_->~LmWorkspace();
    if (lm_result_ != nullptr) lm_result_->~LmResult();
    if (reliability_ != nullptr) reliability_->~ReliabilityWorkspace();
    cost_ = nullptr;
    abc_ = nullptr;
    gsa_ = nullptr;
    lm_ = nullptr;
    lm_result_ = nullptr;
    reliability_ = nullptr;
  }
  TraceBase& trace(std::size_t index) override { return traces_[index]; }
  CalibrationOutlierList& outlier_list(std::size_t which) override { return outlier_lists_[which]; }
  Span<std::uint32_t> subset_room() override { return Span<std::uint32_t>(subset_); }

 private:
  /// The population phase's cost after its solver of `solver_bytes`, over the rest of the phase.
  Paper6CostBase* open_cost(std::size_t solver_bytes) {
    unsigned char* at = arena_ + detail::arena_round(solver_bytes);
    const std::size_t count = cost_values(samples_);
    // Left uninitialised here: the cost zeroes its storage itself. (An array new of a type
    // with a trivial destructor adds no cookie.)
    double* values = new (at + detail::arena_round(sizeof(Paper6CostView))) double[count];
    cost_ = new (at) Paper6CostView(Span<double>(values, count), kMaxLinkLengths);
    return cost_;
  }

  unsigned char* arena_ = nullptr;  // the caller's
  std::size_t samples_ = 0;
  Trace<TraceCapacity> traces_[kMaxCalibrationStages];
  CalibrationOutlierList outlier_lists_[2];
  std::uint32_t subset_[kMaxPopulationSubset] = {};
  Paper6CostView* cost_ = nullptr;  // the open phase's objects, built in the arena
  Abc* abc_ = nullptr;
  Gsa* gsa_ = nullptr;
  LmWorkspace* lm_ = nullptr;
  LmResult* lm_result_ = nullptr;
  ReliabilityWorkspace* reliability_ = nullptr;
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
