#include "textio/ur_kinematics.hpp"

#include <cmath>

#include "textio/text_util.hpp"
#include "textio/urdf.hpp"

namespace hivecal::textio {
namespace {

const char* const kFrameNames[kSixJoints] = {"shoulder", "upper_arm", "forearm", "wrist_1", "wrist_2", "wrist_3"};

/// Moves joint k's frame along its axis so that its d becomes 0 (see the header): the link
/// part ends where joint k+1's axis meets joint k's x-y plane, joint k+1's d takes the rest.
void move_along_axis(int k, const double theta_k, const double alpha_k, RigidTransform* joint, RigidTransform* link,
                     RigidTransform* next_joint) {
  if (joint[k].translation_m.z() == 0.0) return;
  const RigidTransform to_next = joint[k].then_after(link[k]);
  const Vec3 next_axis = to_next.rotation * Vec3::UnitZ();
  const double along_m = -to_next.translation_m.z() / next_axis.z();  // checked non-parallel by the caller
  const Vec3 meet = to_next.translation_m + along_m * next_axis;      // z = 0: in joint k's x-y plane
  // UR's arm links point along -x (negative a): the same sign here, exact in every quadrant.
  const double heading_rad = std::atan2(-meet.y(), -meet.x());
  const double length_m = -std::hypot(meet.x(), meet.y());
  joint[k] = RigidTransform{rotation_z(heading_rad), Vec3::Zero()};
  link[k] = RigidTransform{rotation_z(theta_k - heading_rad) * rotation_x(alpha_k), Vec3(length_m, 0.0, 0.0)};
  next_joint->translation_m.z() -= along_m;
}

std::string entry(const char* name, const RigidTransform& frame) {
  UrdfOrigin o = urdf_origin(frame);
  o.xyz_m += Vec3::Zero();  // -0 reads as 0
  o.rpy_rad += Vec3::Zero();
  return std::string("  ") + name + ":\n    x: " + format_double(o.xyz_m.x()) +
         "\n    y: " + format_double(o.xyz_m.y()) + "\n    z: " + format_double(o.xyz_m.z()) +
         "\n    roll: " + format_double(o.rpy_rad.x()) + "\n    pitch: " + format_double(o.rpy_rad.y()) +
         "\n    yaw: " + format_double(o.rpy_rad.z()) + "\n";
}

}  // namespace

bool ur_kinematics_from_model(const RobotModel& model, UrKinematics* kinematics, std::string* why) {
  constexpr double kAxisTolerance = 0.1;  // sin or cos of a twist [-]
  const DhJoint* j = model.joints;
  if (!(std::fabs(std::cos(j[0].alpha_rad)) < kAxisTolerance && std::fabs(std::sin(j[1].alpha_rad)) < kAxisTolerance &&
        std::fabs(std::sin(j[2].alpha_rad)) < kAxisTolerance)) {
    *why =
        "not a UR-shaped arm (joint 2 perpendicular to joint 1, joints 2, 3 and 4 parallel): the UR kinematics "
        "YAML describes UR arms only; use --format urdf";
    return false;
  }
  RigidTransform joint[kSixJoints];
  RigidTransform link[kSixJoints];
  for (int i = 0; i < kSixJoints; ++i) {
    joint[i] = RigidTransform{rotation_z(j[i].theta_offset_rad), Vec3(0.0, 0.0, j[i].d_m)};
    link[i] = RigidTransform{rotation_x(j[i].alpha_rad), Vec3(j[i].a_m, 0.0, 0.0)};
  }
  for (int k = 1; k <= 2; ++k) {  // the parallel joints 2 and 3
    move_along_axis(k, j[k].theta_offset_rad, j[k].alpha_rad, joint, link, &joint[k + 1]);
  }
  kinematics->joint_frames[0] = joint[0];
  for (int i = 1; i < kSixJoints; ++i) kinematics->joint_frames[i] = link[i - 1].then_after(joint[i]);
  kinematics->flange = link[kSixJoints - 1];
  return true;
}

std::string format_ur_kinematics_yaml(const UrKinematics& kinematics, const std::string& hash) {
  std::string s = "# Written by hivecal export (ROS UR description / driver kinematics parameters).\nkinematics:\n";
  for (int i = 0; i < kSixJoints; ++i) s += entry(kFrameNames[i], kinematics.joint_frames[i]);
  return s + "  hash: " + hash + "\n";
}

}  // namespace hivecal::textio
