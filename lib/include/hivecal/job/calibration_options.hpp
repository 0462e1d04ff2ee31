// The settings of a calibration job (calibration.hpp, the job's one entry): the method and
// what LM may move, the split, the population solvers, the significance test, the blunder
// search, the joint terms (docs/compliance.md), the prior and the frames (docs/robust.md).
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/core/status.hpp"
#include "hivecal/core/types.hpp"
#include "hivecal/model/compliance.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/solve/paper6_cost.hpp"
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
  /// chance at most kHarmonicFamilyAlpha of the time (24 terms: 3.53; each family's level:
  /// JointTermFamily::level) [-].
  double significance_t = 3.0;
};

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

/// Lower-case name of a method as the command line spells it ("abc+lm", "all", ...).
const char* calibration_method_name(CalibrationMethod method);

/// The names calibration_method_from_name accepts, for messages and help:
/// "abc+lm, gsa+lm, lm, abc, gsa, all" (the default first).
const char* calibration_method_names();

/// The method a name spells (calibration_method_name's inverse). Errors: invalid_argument
/// (null or unknown name; *method unchanged).
Status calibration_method_from_name(const char* name, CalibrationMethod* method);

}  // namespace hivecal
