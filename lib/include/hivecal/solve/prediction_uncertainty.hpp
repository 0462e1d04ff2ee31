// How well a calibration predicts a pose, and the poses it was made on: the 1-sigma of a
// predicted point from the parameters' covariance (parameter_correlation.hpp,
// parameter_covariance), the domain of the training poses (joint ranges, the tool's
// orientation spread, the typical sigma there) and whether a pose lies outside it
// (docs/robust.md, "Prediction uncertainty and the calibration's domain").
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/core/status.hpp"
#include "hivecal/core/types.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/model/full_params.hpp"
#include "hivecal/solve/normal_equations.hpp"

namespace hivecal {

/// The frame a predicted point is given in.
enum class PredictionFrame : std::uint8_t {
  tracker,  ///< base_to_tracker * FK(q) * tool: the base's uncertainty counts
  base,     ///< FK(q) * tool in the robot base frame: the base's does not
};

/// 1-sigma per axis of the point of target `target` (0-based) predicted at `q_rad`:
/// sqrt(trace(J C J^T) / 3), J = d(predicted point) / d(full parameters) (3 x P) at `model` /
/// `base_to_tracker`, C = `covariance` over the parameters of `estimated` (the others count 0;
/// the base's columns are 0 in PredictionFrame::base). trace(J C J^T) is the expected squared
/// 3-D error, the same in any frame; divided by 3 it is the mean variance of an axis. For a
/// target > 0 its tool point is not among the parameters: target 1's tool columns are 0, and
/// `target_tool_sigma_m` (that tool point's own 1-sigma per axis, LmResult::other_tools_sigma_m)
/// adds its variances (its covariance with the others is left out) [m].
double prediction_sigma_m(const RobotModel& model, const RigidTransform& base_to_tracker, const JointVector& q_rad,
                          int target, const NormalMatrix& covariance, ParamMask estimated,
                          PredictionFrame frame = PredictionFrame::tracker,
                          const Vec3& target_tool_sigma_m = Vec3::Zero());

/// Beyond this multiple of the training poses' typical sigma (CalibrationDomain::typical_sigma_m)
/// a prediction is an extrapolation: the model there rests on directions the training poses
/// hardly determined [-].
inline constexpr double kExtrapolationSigmaFactor = 3.0;
/// A joint that the model's joint terms depend on (CalibrationDomain::term_joints) further than
/// this beyond its training range makes a prediction an extrapolation: what the terms fit over
/// the range (a harmonic of the joint's reading, a deflection) is not known beyond it [rad]
/// (5 degrees). A rigid chain's geometry holds at any reading: its joints' ranges do not count.
inline constexpr double kExtrapolationJointMargin_rad = 0.08726646259971647;
/// The tool axis (flange z) further than this beyond the training poses' spread from their mean
/// direction makes a prediction an extrapolation: the tool point's component along a direction
/// the axis never took is not determined by the poses (a dropped or barely estimated tool
/// point that the covariance does not hold) [rad] (5 degrees).
inline constexpr double kExtrapolationToolAxisMargin_rad = 0.08726646259971647;

/// The poses a calibration was made on: what its predictions can be trusted within.
struct CalibrationDomain {
  std::size_t poses = 0;                            ///< poses summarised (distinct joint readings) [-]
  JointVector joint_min_rad = JointVector::Zero();  ///< smallest reading of each joint [rad]
  JointVector joint_max_rad = JointVector::Zero();  ///< largest reading of each joint [rad]
  Vec3 tool_axis_mean = Vec3::Zero();               ///< mean direction of the flange z axis in the base frame [-]
  double tool_axis_spread_rad = 0.0;                ///< largest angle of the flange z axis from that mean [rad]
  double tool_axis_rms_rad = 0.0;                   ///< its RMS angle from the mean [rad]
  double typical_sigma_m = 0.0;                     ///< sqrt(mean prediction_sigma_m^2) over the poses [m]
  double max_sigma_m = 0.0;                         ///< largest prediction_sigma_m over the poses [m]
  unsigned term_joints = 0;  ///< bit j: the model's joint terms depend on joint j's reading (term_joint_mask)
  double sigma_factor = kExtrapolationSigmaFactor;                 ///< the extrapolation's sigma multiple [-]
  double joint_margin_rad = kExtrapolationJointMargin_rad;         ///< the extrapolation's joint margin [rad]
  double tool_axis_margin_rad = kExtrapolationToolAxisMargin_rad;  ///< the extrapolation's tool axis margin [rad]
};

/// The joints whose readings the joint terms of `model` with a non-zero coefficient depend on
/// (bit j for joint j): a harmonic's own joint; a gravity term's, every joint whose turning by
/// 0.1 rad changes its basis at one of (up to 16 of) `samples`' poses (for a floor mount all
/// but joint 1). 0 for a rigid model.
unsigned term_joint_mask(const RobotModel& model, Span<const Sample> samples);

/// Poses whose prediction sigma the domain's typical and largest sigma are taken over at most:
/// evenly spaced among more (the RMS of a few thousand is the RMS of all to a few per cent, and
/// a large set costs no more than this) [-].
inline constexpr std::size_t kDomainSigmaPoses = 2048;

/// The domain of `samples` (each run of samples at equal joints is one pose, its target 1
/// point or, without one, its first sample's target) under `model` / `base_to_tracker` and the
/// parameter covariance (`covariance` over `estimated`; target_tool_sigma_m as in
/// prediction_sigma_m, indexed by target - 1): the joint ranges and the tool axis over every
/// pose, the sigmas over every pose up to kDomainSigmaPoses, else over that many evenly spaced.
/// Errors: dataset_empty, non_finite_input.
Status calibration_domain(const RobotModel& model, const RigidTransform& base_to_tracker, Span<const Sample> samples,
                          const NormalMatrix& covariance, ParamMask estimated,
                          const Vec3 (&other_tools_sigma_m)[kMaxTargets - 1], CalibrationDomain* domain);

/// Why a prediction is an extrapolation: its sigma beyond the domain's multiple of the typical
/// one, the tool axis beyond the training spread by more than its margin, a joint that the
/// terms depend on beyond its range by more than the margin; none: inside.
struct Extrapolation {
  bool sigma_beyond = false;         ///< sigma_m > sigma_factor x typical_sigma_m
  bool tool_axis_beyond = false;     ///< tool_axis_angle_rad > tool_axis_spread_rad + tool_axis_margin_rad
  double tool_axis_angle_rad = 0.0;  ///< the flange z axis's angle from the training mean direction [rad]
  int joint = -1;                    ///< 0-based term joint furthest beyond its range by more than the margin; -1: none
  double joint_beyond_rad = 0.0;     ///< how far that joint is beyond its range [rad]
  /// Any reason holds.
  bool extrapolated() const { return sigma_beyond || tool_axis_beyond || joint >= 0; }
};

/// Whether a pose `q_rad` of `model` whose prediction has 1-sigma `sigma_m` lies outside
/// `domain` (a domain without a typical sigma, 0, tests the tool axis and the joints only).
Extrapolation extrapolation(const CalibrationDomain& domain, const RobotModel& model, const JointVector& q_rad,
                            double sigma_m);

}  // namespace hivecal
