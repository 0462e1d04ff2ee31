// A UR-shaped arm as the `kinematics:` YAML of the ROS UR description and driver
// (docs/formats.md "ROS UR kinematics export").
//
// Each standard-DH row i splits into a joint part J_i = Rz(theta_i) Tz(d_i) and a link part
// L_i = Tx(a_i) Rx(alpha_i); the YAML's six frames are J_1, L_1 J_2, ..., L_5 J_6 (shoulder,
// upper_arm, forearm, wrist_1, wrist_2, wrist_3), each followed by the joint's Rz(q_i); L_6 (the
// flange offset a_6, alpha_6) has no entry. Before that, as UR's own converter does it, the
// parallel joints 2 and 3 have their frames moved along their axes: d_i is set to 0, the link
// part's end moves along the next joint's axis to where that axis meets joint i's x-y plane
// (the link's new length and direction from atan2, any quadrant), and the next joint's d takes
// the difference. The chain is unchanged; the cancelling offsets of a real factory calibration
// (hundreds of metres in d_2 .. d_4) are gone. rpy is URDF's (R = Rz(yaw) Ry(pitch) Rx(roll)).
#pragma once

#include <string>

#include "hivecal/core/types.hpp"
#include "hivecal/model/kinematics.hpp"

namespace hivecal::textio {

/// The six joint frames of the YAML and the flange offset it cannot hold.
struct UrKinematics {
  RigidTransform joint_frames[kSixJoints];  ///< shoulder .. wrist_3: previous link -> joint frame (before Rz(q_i))
  RigidTransform flange;                    ///< L_6 = Tx(a_6) Rx(alpha_6): not in the YAML (identity on UR arms)
};

/// The YAML frames of `model` (standard DH); false with *why when the arm is not UR-shaped
/// (joint 2 perpendicular to joint 1, joints 2, 3 and 4 parallel, within 0.1 rad).
bool ur_kinematics_from_model(const RobotModel& model, UrKinematics* kinematics, std::string* why);

/// The YAML document: `kinematics:` with the six frames (x y z roll pitch yaw) and `hash`.
std::string format_ur_kinematics_yaml(const UrKinematics& kinematics, const std::string& hash);

}  // namespace hivecal::textio
