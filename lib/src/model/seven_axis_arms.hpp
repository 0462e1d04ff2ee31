// Internals of the built-in arms (library-private): the seven-axis arms' published tables
// (seven_axis_arms.cpp), which kinematics.cpp serves beside Universal Robots' own. A build of
// six joints (HIVECAL_MAX_JOINTS < 7) compiles none of them in: it knows no such type.
#pragma once

#include "hivecal/model/kinematics.hpp"

namespace hivecal::detail {

/// The nominal model of a built-in seven-axis type into *model (its standard-DH chain, the tool
/// point at the maker's flange): true, or false for a type that is not one (a UR).
bool seven_axis_model(RobotType type, RobotModel* model);
/// Lower-case name of a built-in seven-axis type ("iiwa14"), or nullptr for a type that is not one.
const char* seven_axis_name(RobotType type);

}  // namespace hivecal::detail
