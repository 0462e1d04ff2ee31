#include "textio/ur_kinematics.hpp"

#include <cmath>

#include "textio/text_util.hpp"
#include "textio/ur_calibration_conf.hpp"
#include "textio/urdf.hpp"

namespace hivecal::textio {
namespace {

const char* const kFrameNames[kSixJoints] = {"shoulder", "upper_arm", "forearm", "wrist_1", "wrist_2", "wrist_3"};

constexpr double kAxisTolerance = 0.1;  // sin or cos of a twist that makes two axes parallel or perpendicular [-]

/// -x, exactly, and +0 for 0 (a -0 would be written as such).
double negated(double x) {
  return 0.0 - x;
}

/// x and y negated: a point or direction in a frame turned by pi about its z.
Vec3 turned(const Vec3& v) {
  return Vec3(negated(v.x()), negated(v.y()), v.z());
}

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

bool is_ur_table(const RobotModel& model) {
  const DhJoint* j = model.joints;
  return has_ur_joints(model) && std::sin(j[0].alpha_rad) > 1.0 - kAxisTolerance &&
         std::fabs(std::sin(j[1].alpha_rad)) < kAxisTolerance && std::fabs(std::sin(j[2].alpha_rad)) < kAxisTolerance &&
         std::sin(j[3].alpha_rad) > 1.0 - kAxisTolerance && std::sin(j[4].alpha_rad) < kAxisTolerance - 1.0 &&
         j[1].a_m < 0.0 && j[2].a_m < 0.0;
}

RobotModel turned_by_pi(const RobotModel& model) {
  // Rz(pi) Rz(q + theta) Tz(d) Tx(-a) Rx(-alpha) = Rz(q + theta) Tz(d) Tx(a) Rx(alpha) Rz(pi): each
  // row carries the turn to the next frame, so the chain ends turned by pi as well.
  RobotModel out = model;
  for (DhJoint& joint : out.joints) {
    joint.a_m = negated(joint.a_m);
    joint.alpha_rad = negated(joint.alpha_rad);
  }
  for (int k = 0; k < kMaxTargets; ++k) target_tool(&out, k) = turned(target_tool(model, k));
  ComplianceModel& compliance = out.compliance;
  compliance.gravity_direction = turned(compliance.gravity_direction);
  for (Vec3& com_m : compliance.masses.link_com_m) com_m = turned(com_m);
  compliance.masses.payload_com_m = turned(compliance.masses.payload_com_m);
  return out;
}

bool is_ur_table_turned(const RobotModel& model) {
  return !is_ur_table(model) && is_ur_table(turned_by_pi(model));
}

bool ur_kinematics_from_model(const RobotModel& model_as_given, UrKinematics* kinematics, std::string* why) {
  if (!has_ur_joints(model_as_given)) {
    *why = "the UR kinematics YAML describes UR arms (six revolute joints); this arm has " +
           joint_shape(model_as_given) + ": use --format urdf";
    return false;
  }
  const RobotModel model = is_ur_table_turned(model_as_given) ? turned_by_pi(model_as_given) : model_as_given;
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
