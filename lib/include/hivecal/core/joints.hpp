// The joint count of the arms the library models, without Eigen (the wire records use it).
#pragma once

namespace hivecal {

/// Number of joints of the serial arms the library models (6-axis arms).
inline constexpr int kJointCount = 6;

}  // namespace hivecal
