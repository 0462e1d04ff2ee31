// Inverse kinematics of a flange pose: the joints that put the flange frame at a commanded
// pose, within joint limits. A damped Gauss-Newton on the 6-D pose error (position, and the
// rotation vector of the remaining turn) with a numeric Jacobian, from seeded random starts:
// any chain of the model (a redundant one too: the damped step chooses among the solutions), no
// closed form needed, and the same bits on every target.
#pragma once

#include "hivecal/core/random.hpp"
#include "hivecal/core/status.hpp"
#include "hivecal/core/types.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/plan/pose_plan.hpp"

namespace hivecal {

/// Settings of the search.
struct InverseKinematicsOptions {
  int starts = 12;                     ///< random starts within the limits before giving up [-]
  int iterations = 60;                 ///< Gauss-Newton steps per start [-]
  double position_tolerance_m = 1e-6;  ///< converged when the position error is below this [m]
  double angle_tolerance_rad = 1e-6;   ///< ... and the remaining turn below this [rad]
  double damping = 1e-6;               ///< added to the normal matrix's diagonal (near singular poses) [-]
};

/// The rotation vector (axis times angle, angle in [0, pi]) of rotation matrix `r` [rad].
Vec3 rotation_vector_of(const Mat3& r);

/// Joints that put the flange of `model` at `target` (robot base frame), every joint within
/// `limits` (a turn more or less is the same pose: each revolute joint is wrapped into its range
/// when it can be). Starts are drawn from `random`. Errors: not_converged (no start reached the
/// tolerances inside the limits), invalid_argument (options), non_finite_input (target).
Status solve_flange_pose(const RobotModel& model, const JointLimits& limits, const RigidTransform& target,
                         const InverseKinematicsOptions& options, Random* random, JointVector* q_out);

}  // namespace hivecal
