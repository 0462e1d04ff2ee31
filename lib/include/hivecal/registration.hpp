// Registration without recalibration: a calibrated arm carried to a new tracker setup. Only
// the base -> tracker transform (RegistrationFit::base), or it and every target's tool point
// (RegistrationFit::frames), is fitted to new samples by LM on those parameters
// (LmParamSet::custom), every other parameter and every model term (compliance, harmonics) of
// the calibration applied as it is. The result says how well the samples determine the
// registration (the base's 1-sigma from its covariance, the condition, the points' spread)
// and which of its poses the w-test set aside; carry_covariance() takes the calibration's
// parameter covariance through it (docs/robust.md, "Registration").
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/core/status.hpp"
#include "hivecal/core/types.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/model/full_params.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/solve/parameter_correlation.hpp"
#include "hivecal/solve/reliability.hpp"

namespace hivecal {

/// What a registration fits.
enum class RegistrationFit : std::uint8_t {
  base,    ///< the base -> tracker transform (6 parameters)
  frames,  ///< the base and every target's tool point (a reflector set anew)
};

/// Lower-case name of a fit ("base", "frames").
const char* registration_fit_name(RegistrationFit fit);
/// The parameters a fit moves in those of `model` (with kOtherTargetTools for frames).
ParamMask registration_mask(RegistrationFit fit, const RobotModel& model);

/// Settings of a registration.
struct RegistrationOptions {
  RegistrationFit fit = RegistrationFit::base;  ///< what is fitted
  LmOptions lm;                                 ///< iterations, tolerances, loss; its params and mask are set here
  bool find_blunders = true;                    ///< w-test of the poses, the failing ones set aside one at a time
  BlunderTestOptions blunder_test;              ///< significance, tracker sigma, redundancy floor
  /// Largest share of the poses the w-test sets aside (at least one); more failing is the
  /// model's error (the calibration does not hold here) and none is set aside [-].
  double max_blunder_share = 0.05;
};

/// The fitted points' second principal spread below this share of the first: nearly
/// collinear, the rotation about their line barely determined [-].
inline constexpr double kRegistrationCollinearRatio = 0.05;
/// The fitted points' RMS distance from their centroid below this: a small spread, the
/// rotation's lever short [m].
inline constexpr double kRegistrationMinSpread_m = 0.1;
/// Fewer residual degrees of freedom than this: the sigmas rest on few residuals [-].
inline constexpr int kRegistrationMinResidualDof = 6;
/// The column-scaled normal matrix of the registered parameters beyond this condition number:
/// their directions barely separable [-].
inline constexpr double kRegistrationMaxCondition = 1e4;
/// Poses the w-test sets aside at most [-].
inline constexpr std::size_t kMaxRegistrationBlunders = 16;

/// Why a registration is weakly determined (bits of RegistrationResult::weakness).
enum RegistrationWeakness : unsigned {
  kRegistrationNearlyCollinear = 1U,  ///< kRegistrationCollinearRatio
  kRegistrationSmallSpread = 2U,      ///< kRegistrationMinSpread_m
  kRegistrationFewResiduals = 4U,     ///< kRegistrationMinResidualDof
  kRegistrationIllConditioned = 8U,   ///< kRegistrationMaxCondition
  kRegistrationUndetermined = 16U,    ///< a registered parameter was dropped: kept at its start value
};

/// What the w-test did with the registration's poses.
enum class RegistrationBlunderVerdict : std::uint8_t {
  none,         ///< no pose failed
  set_aside,    ///< the failing poses were set aside, one at a time
  model_error,  ///< more poses failed than max_blunder_share: none set aside (the calibration does not hold here)
  not_tested,   ///< off, or the fit leaves too little redundancy for the test
};

/// Lower-case name of a verdict ("none", "set_aside", "model_error", "not_tested").
const char* registration_blunder_verdict_name(RegistrationBlunderVerdict verdict);

/// A pose the w-test set aside.
struct RegistrationBlunder {
  std::uint32_t index = 0;    ///< Sample::index of its first sample [-]
  std::uint32_t samples = 0;  ///< its samples [-]
  double w = 0.0;             ///< its w [-]
  double critical_w = 0.0;    ///< the threshold it exceeded [-]
  double residual_m = 0.0;    ///< its largest 3-D residual [m]
};

/// A registration's answer (~45 kB with the covariance at the hosted capacity: keep it in the
/// caller's storage).
struct RegistrationResult {
  RobotModel model;                ///< the calibration with the registered tool points (frames), else as given
  RigidTransform base_to_tracker;  ///< the registered base -> tracker transform
  RegistrationFit fit = RegistrationFit::base;  ///< what was fitted
  ParamMask estimated = 0;  ///< the registered parameters estimated (kOtherTargetTools: the other tool points)
  ParamMask dropped = 0;    ///< registered parameters the samples do not determine, kept at their start values
  /// Covariance of the registered parameters (sigma_hat^2 (J^T J)^-1 over `estimated`, 0
  /// elsewhere) [m^2], [m rad], [rad^2].
  NormalMatrix covariance;
  Vec3 rotation_sigma_rad = Vec3::Zero();   ///< 1-sigma of the base rotation about the base's x, y, z [rad]
  Vec3 translation_sigma_m = Vec3::Zero();  ///< 1-sigma of the base translation at the base origin [m]
  Vec3 tool_sigma_m = Vec3::Zero();         ///< frames: 1-sigma of target 1's tool point [m]
  Vec3 other_tools_sigma_m[kMaxTargets - 1] = {Vec3::Zero(), Vec3::Zero()};  ///< frames: targets 2.. [m]
  /// The registration's own 1-sigma at its points: sqrt(mean prediction_sigma_m^2) over the
  /// fitted poses under `covariance` alone [m].
  double point_sigma_m = 0.0;
  double condition = 0.0;          ///< condition number of the column-scaled normal matrix of `estimated` [-]
  double spread_m = 0.0;           ///< RMS distance of the fitted points from their centroid [m]
  double collinearity = 0.0;       ///< second principal spread of the fitted points over the first [-]
  unsigned weakness = 0;           ///< RegistrationWeakness bits; 0: well determined
  std::size_t fitted_samples = 0;  ///< samples fitted (the first of the span after the call) [-]
  std::size_t fitted_poses = 0;    ///< poses fitted (runs of samples at equal joints) [-]
  double rms_m = 0.0;              ///< RMS 3-D residual of the fitted samples [m]
  double residual_sigma_m = 0.0;   ///< sigma_hat per axis [m]
  int residual_dof = 0;            ///< 3 N - registered parameters [-]
  double huber_threshold_m = 0.0;  ///< the fit's Huber k (its loss; 0: least squares) [m]
  int iterations = 0;              ///< LM iterations of the last fit [-]
  LmTermination termination = LmTermination::max_iterations;                    ///< why the last fit stopped
  RegistrationBlunderVerdict verdict = RegistrationBlunderVerdict::not_tested;  ///< the w-test's verdict
  std::size_t failing_poses = 0;  ///< poses failing the w-test in the first round (model_error: all kept) [-]
  RegistrationBlunder blunders[kMaxRegistrationBlunders];  ///< the poses set aside, in order
  std::size_t blunder_count = 0;                           ///< [-]

  bool weak() const { return weakness != 0; }  ///< any weakness
};

/// Scratch of a registration (~300 kB at the hosted capacity): the caller's memory plan.
struct RegistrationWorkspace {
  LmWorkspaceWithTargets lm;         ///< the fit's
  LmResult fit;                      ///< the last fit's result
  CorrelationScratch covariance;     ///< the covariance's and carry_covariance's
  ReliabilityWorkspace reliability;  ///< the w-test's
};

/// Registers `calibrated` on `samples`: starts from the rigid (Kabsch) fit of the base (frames:
/// with the other targets' tool points in closed form) and refines the registered parameters
/// by LM, the rest of the model as given. With find_blunders the w-test of each pose follows
/// (the poses of several readings tested whole); a failing pose is moved behind the others and
/// the fit repeated, the worst first, while no more than max_blunder_share of the poses fail.
/// `samples` is reordered: the first result->fitted_samples are the fitted ones, in their
/// order, the set-aside ones behind them. Errors: dataset_empty, too_few_samples (3 N <= the
/// registered parameters), degenerate_geometry (fewer than 3 non-collinear points),
/// non_finite_input, invalid_argument, and LM's.
Status register_frames(const RobotModel& calibrated, Span<Sample> samples, const RegistrationOptions& options,
                       RegistrationWorkspace* workspace, RegistrationResult* result);

/// The covariance of a calibration carried through its registration: the registered
/// parameters B move with the others theta, b = G theta + noise, G = -H_BB^-1 H_B,theta the
/// registration's normal equations at its result on `fitted` (B's columns of
/// registration.estimated, theta = `estimated` without B). So C' = [C_tt, C_tt G^T; G C_tt,
/// G C_tt G^T + C_reg] over estimated | B: a parameter the registered base absorbs (theta1 by
/// base_rz) no longer moves a prediction. `calibrated_covariance` (over `estimated`) and
/// *covariance may be the same matrix. *carried_estimated: estimated | B. Errors:
/// dataset_empty, non_finite_input, singular_system.
Status carry_covariance(const RegistrationResult& registration, Span<const Sample> fitted, ParamMask estimated,
                        const NormalMatrix& calibrated_covariance, CorrelationScratch* scratch,
                        NormalMatrix* covariance, ParamMask* carried_estimated);

}  // namespace hivecal
