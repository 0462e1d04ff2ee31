#include "hivecal/model/ur_deltas.hpp"

#include "hivecal/core/math.hpp"

namespace hivecal {

Status apply_ur_deltas(const RobotModel& nominal, const UrCalibrationDeltas& deltas, RobotModel* calibrated) {
  if (!has_ur_joints(nominal)) return Status::invalid_argument;
  RobotModel out = nominal;
  for (int j = 0; j < kSixJoints; ++j) {
    const double values[] = {deltas.delta_theta_rad[j], deltas.delta_a_m[j], deltas.delta_d_m[j],
                             deltas.delta_alpha_rad[j]};
    for (double v : values) {
      if (!math::is_finite(v)) return Status::non_finite_input;
    }
    out.joints[j].theta_offset_rad += deltas.delta_theta_rad[j];
    out.joints[j].a_m += deltas.delta_a_m[j];
    out.joints[j].d_m += deltas.delta_d_m[j];
    out.joints[j].alpha_rad += deltas.delta_alpha_rad[j];
  }
  *calibrated = out;
  return Status::ok;
}

UrCalibrationDeltas ur_deltas_between(const RobotModel& nominal, const RobotModel& calibrated) {
  UrCalibrationDeltas deltas;
  for (int j = 0; j < kSixJoints; ++j) {
    deltas.delta_theta_rad[j] = calibrated.joints[j].theta_offset_rad - nominal.joints[j].theta_offset_rad;
    deltas.delta_a_m[j] = calibrated.joints[j].a_m - nominal.joints[j].a_m;
    deltas.delta_d_m[j] = calibrated.joints[j].d_m - nominal.joints[j].d_m;
    deltas.delta_alpha_rad[j] = calibrated.joints[j].alpha_rad - nominal.joints[j].alpha_rad;
  }
  return deltas;
}

}  // namespace hivecal
