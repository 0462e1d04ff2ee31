// A model's shape, checked once per job (compiled for size on bare metal, lib/CMakeLists.txt);
// the kinematics it guards are kinematics.cpp.
#include "hivecal/model/kinematics.hpp"

namespace hivecal {

Status check_joint_layout(const RobotModel& model) {
  if (model.joint_count < 1 || model.joint_count > kMaxJoints) return Status::invalid_argument;
  if (model.joint_count < 32 && (model.prismatic_joints >> static_cast<unsigned>(model.joint_count)) != 0) {
    return Status::invalid_argument;
  }
  for (int j = model.joint_count; j < kMaxJoints; ++j) {
    const DhJoint& unused = model.joints[j];
    if (unused.theta_offset_rad != 0.0 || unused.d_m != 0.0 || unused.a_m != 0.0 || unused.alpha_rad != 0.0) {
      return Status::invalid_argument;
    }
  }
  return Status::ok;
}

}  // namespace hivecal
