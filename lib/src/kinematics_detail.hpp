// Internals of the kinematics (library-private): the Jacobian kernel that writes its columns
// straight into the row buffers of the normal-equation update (full_model.cpp), so that the
// hot loop needs no 3 x 27 matrix and no copy.
#pragma once

#include "hivecal/kinematics.hpp"

namespace hivecal::detail {

/// Where tool_point_jacobian_rows writes: column c of the 3 x 27 Jacobian goes to
/// row[r][slot[c]], r = 0..2. Any permutation works; unwanted columns may point at scratch.
struct JacobianRowsTarget {
  double* row[3];                 ///< start of the x, y and z rows
  const int* slot;                ///< position of each of the 27 model columns in the rows
};

/// Tool point in the robot base frame [m]; writes d(tool point)/d(model parameters) to
/// `target`. Same values as tool_point_jacobian.
Vec3 tool_point_jacobian_rows(const RobotModel& model, const ModelTrig& model_trig, const JointTrig& joint_trig,
                              const JacobianRowsTarget& target);

}  // namespace hivecal::detail
