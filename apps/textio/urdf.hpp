// A calibrated (or nominal) arm as a URDF serial chain (docs/formats.md "URDF export").
//
// Links: base_link (the description's own base frame) -> [dh_base: the modified-DH offset
// Rx(alpha_0) Tx(a_0), identity for standard DH] -> link_1 .. link_n (n: the model's joint count;
// link_i: the DH frame of joint i after its motion q_i) -> flange (DH frame n) -> tcp (target 1's
// tool point, no rotation) [-> tcp_2, tcp_3 for further targets]; with a base -> tracker
// transform, a fixed `tracker` link under base_link at the tracker's pose. Each joint_i turns
// (revolute) or slides (prismatic) along z of its origin frame: origin_1 = base offset *
// Rz(theta_1), origin_i = Tz(d) Tx(a) Rx(alpha) of row i-1 * Rz(theta_i). URDF's rpy is
// R = Rz(yaw) Ry(pitch) Rx(roll) (fixed axes x, y, z).
// What URDF cannot hold (compliance terms) is left out: the caller says so.
#pragma once

#include <string>
#include <string_view>

#include "hivecal/core/types.hpp"
#include "textio/robot_description.hpp"

namespace hivecal::textio {

/// URDF's xyz + rpy of a rigid transform (roll, pitch, yaw [rad], with R = Rz(yaw) Ry(pitch)
/// Rx(roll); at pitch = +-pi/2 roll is 0 and yaw carries the rest).
struct UrdfOrigin {
  Vec3 xyz_m = Vec3::Zero();    ///< translation [m]
  Vec3 rpy_rad = Vec3::Zero();  ///< roll, pitch, yaw [rad]
};

/// The xyz/rpy of `transform`.
UrdfOrigin urdf_origin(const RigidTransform& transform);
/// The transform of an xyz/rpy pair (the inverse of urdf_origin up to rounding).
RigidTransform urdf_transform(const UrdfOrigin& origin);

/// Joint limits written into every joint when the description gives none (effort and velocity
/// always: URDF requires them, a description holds none).
struct UrdfLimits {
  double lower_rad = -6.283185307179586;  ///< a revolute joint's [rad] (UR arms: +-360 deg)
  double upper_rad = 6.283185307179586;   ///< a revolute joint's [rad]
  double effort_nm = 150.0;               ///< a revolute joint's [N m] (URDF requires a value)
  double velocity_rad_s = 3.15;           ///< a revolute joint's [rad/s] (URDF requires a value)
  double lower_m = -6.283185307179586;    ///< a prismatic joint's [m] (a description's default, as for a turn)
  double upper_m = 6.283185307179586;     ///< a prismatic joint's [m]
  double effort_n = 1000.0;               ///< a prismatic joint's [N] (URDF requires a value)
  double velocity_m_s = 1.0;              ///< a prismatic joint's [m/s] (URDF requires a value)
};

/// The URDF document of `robot` (its model, base offset and target tools); `base_to_tracker`
/// (the library's chain base -> tracker, as CalibrationFile holds it) adds the tracker link
/// when not null.
std::string format_urdf(const RobotDescription& robot, const RigidTransform* base_to_tracker,
                        const UrdfLimits& limits = UrdfLimits());

/// Reads a URDF arm (docs/formats.md "URDF in"): 1 .. kMaxJoints revolute, continuous or
/// prismatic joints in one serial chain, fixed joints anywhere, any axis directions; joint 1's
/// axis must meet the root link's x axis at a right angle (a slide's: be at a right angle to it;
/// the DH model's base: identity, or Rx(alpha_0) Tx(a_0) as modified DH). Mimic joints in the
/// chain, floating and planar joints, loops and more joints than kMaxJoints are refused by line.
/// The arm's end: the last joint's child and the links fixed below it; the tool points are its
/// tips named tcp (tcp_2, tcp_3), else tool0, else its only tip; frame n at its 'flange' link
/// when it has one (a 'flange' elsewhere is not the arm's), else at the last joint's child. The
/// DH model's FK is checked against the URDF's on random poses (1e-9 m) or the file is refused;
/// every refusal names the file (and line).
port::Error parse_urdf_description(std::string_view text, const std::string& source_name,
                                   RobotDescription* description);

}  // namespace hivecal::textio
