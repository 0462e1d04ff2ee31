// Universal Robots controller calibration: the [mounting] deltas of calibration.conf that a UR
// controller adds to its nominal DH table, and the deltas that express a calibrated model.
#pragma once

#include "hivecal/core/status.hpp"
#include "hivecal/model/kinematics.hpp"

namespace hivecal {

/// The [mounting] deltas of a UR controller's calibration.conf, one value per joint.
struct UrCalibrationDeltas {
  double delta_theta_rad[kSixJoints] = {};  ///< added to the nominal theta offset (0) [rad]
  double delta_a_m[kSixJoints] = {};        ///< added to the nominal a [m]
  double delta_d_m[kSixJoints] = {};        ///< added to the nominal d [m]
  double delta_alpha_rad[kSixJoints] = {};  ///< added to the nominal alpha [rad]
};

/// True when `model` has a UR's shape: six revolute joints (what calibration.conf describes).
inline bool has_ur_joints(const RobotModel& model) {
  return model.joint_count == kSixJoints && all_revolute(model);
}

/// calibrated = nominal + deltas, field by field; the tool is kept. Status::non_finite_input on
/// NaN/Inf; invalid_argument when `nominal` has not a UR's six revolute joints.
Status apply_ur_deltas(const RobotModel& nominal, const UrCalibrationDeltas& deltas, RobotModel* calibrated);
/// The deltas that turn `nominal` into `calibrated` (inverse of apply_ur_deltas), both of a
/// UR's shape (has_ur_joints; of other arms, the first six joints').
UrCalibrationDeltas ur_deltas_between(const RobotModel& nominal, const RobotModel& calibrated);

}  // namespace hivecal
