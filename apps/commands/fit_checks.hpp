// Plausibility of a finished calibration (docs/cli.md, "Warnings"): parameters that moved more
// than a bound from the uncalibrated geometry, or a test error worse than the baseline's. They
// are warnings, not errors: the result is still written and `calibrate` exits with
// kExitWarnings (5), so a script notices and a person can look.
#pragma once

#include <string>
#include <vector>

#include "hivecal/model/dataset.hpp"

#include "hivecal/calibration.hpp"
#include "report/report.hpp"

namespace hivecal::cli {

/// How far a calibration may move the geometry before it is questioned.
struct FitBounds {
  double max_length_change_m = 0.020;                 ///< d, a and the tool point (--max-change-mm) [m]
  double max_angle_change_rad = 0.03490658503988659;  ///< theta offsets and alpha, 2 deg (--max-change-deg) [rad]
};

/// The training poses against what the model needs (the span warning of fit_warnings).
struct PoseSpan {
  std::size_t poses = 0;        ///< distinct training configurations, at most kDistinctPointLimit [-]
  std::size_t coordinates = 0;  ///< their independent coordinates: 3 per distinct point, less the 3 of the rigid
                                ///< triangle a measured orientation makes of each pose [-]
  int parameters = 0;  ///< what a spread of poses determines of the fit's free parameters (model_parameter_count),
                       ///< with the other targets' tool points when fitted [-]
};

/// Parameters a spread of poses determines for `start` over `free_mask` (rigid: no joint terms;
/// the model's, not the data's): the identifiability analysis (kDefaultIdentifiabilityThreshold)
/// of 48 seeded random configurations, each measured at `targets` targets (start's tool points,
/// held fixed), base at the identity [-]; 0 when the analysis fails.
int model_parameter_count(const RobotModel& start, ParamMask free_mask, int targets);

/// The warnings about `result` (empty when none): one line per parameter of the final stage's
/// model that moved beyond `bounds` from the baseline model (name, both values, the change),
/// one when its training MAE (3D) is above kImplausibleTrainMae_m, and one when the final stage's test MAE (3D) is
/// above the baseline's (only with test samples). `parameters` (Table 4's rows, may be empty): a moved parameter with
/// |correlation| > 0.95 to another says so and what would separate them. Too few poses: with `span`, when its
/// coordinates are no more than the parameters the model has (the identifiability analysis
/// drops what the poses cannot tell apart, so the fit passes through them); without it, when
/// 3 per distinct training point are no more than the parameters the fit determined.
std::vector<std::string> fit_warnings(const CalibrationResult& result, const FitBounds& bounds,
                                      const std::vector<report::ParameterRow>& parameters = {},
                                      const PoseSpan* span = nullptr);

/// Training MAE (3D) of a calibrated model beyond which the model, not the arm, is wrong: a
/// calibrated industrial arm leaves well under a millimetre, its unmodelled effects included;
/// a wrong arm type, joint zero, tool guess or unit leaves centimetres [m].
inline constexpr double kImplausibleTrainMae_m = 0.010;

/// Residual sigma over the measurement noise above which constant orientation columns are
/// said to contradict the positions [-].
inline constexpr double kConstantOrientationNoiseRatio = 10.0;

/// "the orientation columns rx, ry, rz hold one value on every row ..." when they do
/// (`constant`) and the fit's residual sigma is above kConstantOrientationNoiseRatio times the
/// measurement noise; "" otherwise.
std::string constant_orientation_warning(bool constant, double fit_sigma_m, double noise_sigma_m);

/// Training MAE (3D) below which another built-in arm's nominal geometry "explains the data
/// much better": this share of the given one's [-].
inline constexpr double kOtherArmMaeRatio = 1.0 / 3.0;

/// When `start` is a built-in type's nominal geometry (`robot` its name) and the nominal
/// geometry of another built-in type of as many joints (a UR for a UR, a seven-axis arm for a
/// seven-axis one), with the tool points and the base fitted to `train` as
/// the job's baseline is, leaves less than kOtherArmMaeRatio of the training MAE (3D) that
/// `start`'s leaves: "this looks like a ur10 (--robot-model ur10): ..." with both figures; ""
/// otherwise (a description file, no clearly better arm). A few small LM fits (9 parameters).
std::string other_arm_hint(const std::string& robot, const RobotModel& start, Span<const Sample> train);

/// A parameter is held by the prior when its sigma is above its tolerance / sqrt(2): the
/// tolerance tells more about it than the poses do [-].
inline constexpr double kPriorHeldSigmaShare = 0.70710678118654752;

/// One line per DH or tool parameter of `lm` that the nominal model's prior (`tolerances`)
/// holds more than the data do (kPriorHeldSigmaShare): its sigma against its tolerance, and,
/// from `parameters` (Table 4's rows, the data's correlations), the parameter it is most
/// correlated with and what poses would separate them. Empty without a prior.
std::vector<std::string> prior_held_lines(const LmResult& lm, const LmPriorTolerances& tolerances,
                                          const std::vector<report::ParameterRow>& parameters);

/// The line that says the data widened the prior's tolerances from `stated` to `widened`
/// (LmResult::prior_tolerances), each kind by its factor.
std::string prior_widened_line(const LmPriorTolerances& stated, const LmPriorTolerances& widened);

}  // namespace hivecal::cli
