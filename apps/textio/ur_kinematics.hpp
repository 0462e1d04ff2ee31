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

/// True when `model` (standard DH) has six revolute joints and UR's own table's signs: alpha_1 and alpha_4 near +pi/2,
/// alpha_5 near -pi/2, alpha_2 and alpha_3 near 0 (sines within 0.1), a_2 and a_3 negative.
bool is_ur_table(const RobotModel& model);
/// The same arm in frames turned by pi about their z: the base and every DH frame. The chain is
/// unchanged: FK(q) = Rz(pi) * FK_turned(q) (every a and alpha negated, theta and d kept, the
/// tool points' x and y negated, and the compliance's gravity direction and centres of mass
/// likewise). Exact (sign changes only); turning twice gives the model back.
RobotModel turned_by_pi(const RobotModel& model);
/// True when `model` is not UR's table but turned_by_pi makes it UR's (is_ur_table): a UR arm
/// described from a base turned by pi, as ROS's ur_description's base_link is (REP-103: x
/// forward; UR's base: x backward). UR's own formats (calibration.conf deltas, the kinematics
/// YAML) are in UR's base, so such a model is turned before they use it.
bool is_ur_table_turned(const RobotModel& model);

/// The YAML frames of `model` (standard DH; a table turned by pi, is_ur_table_turned, is turned
/// first: the YAML's frames are in UR's base, base_link_inertia); false with *why when the arm
/// is not UR-shaped (joint 2 perpendicular to joint 1, joints 2, 3 and 4 parallel, within 0.1 rad).
bool ur_kinematics_from_model(const RobotModel& model, UrKinematics* kinematics, std::string* why);

/// The YAML document: `kinematics:` with the six frames (x y z roll pitch yaw) and `hash`.
std::string format_ur_kinematics_yaml(const UrKinematics& kinematics, const std::string& hash);

}  // namespace hivecal::textio
