// The joints of the serial arms the library models, without Eigen (the wire records use it):
// the build's joint capacity and what kind of joint each one is.
#pragma once

#include <cstdint>

#include "hivecal/core/capacity.hpp"

namespace hivecal {

/// Joints of the arms with built-in tables (Universal Robots), of the paper's method and of a
/// default-built RobotModel [-].
inline constexpr int kSixJoints = 6;

/// What a joint's reading moves (docs/kinematics.md).
enum class JointType : std::uint8_t {
  revolute = 0,   ///< the reading turns the joint: it adds to the DH theta [rad]
  prismatic = 1,  ///< the reading slides the joint: it adds to the DH d [m]
};

}  // namespace hivecal
