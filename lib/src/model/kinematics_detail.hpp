// Internals of the kinematics (library-private): the Jacobian kernel that writes its columns
// straight into the row buffers of the normal-equation update (full_model.cpp), so that the
// hot loop needs no 3 x 27 matrix and no copy, for as many samples at once as the target has
// double lanes.
#pragma once

#include "hivecal/model/kinematics.hpp"
#include "core/lanes.hpp"

namespace hivecal::detail {

/// The rigid chain's frames at joint readings q (no compliance): frame[0] the base, frame[k]
/// DH frame k (after joint k), frame[model.joint_count] the flange, as fk_flange composes them
/// (the entries beyond it are not written).
void rigid_frames(const RobotModel& model, const JointVector& q_rad, RigidTransform (&frame)[kMaxJoints + 1]);

/// Where tool_point_jacobian_rows writes: column c of the 3 x model_param_count Jacobian goes to
/// row[r][slot[c]], r = 0..2. Any permutation works; unwanted columns may point at scratch.
struct JacobianRowsTarget {
  double* row[3];   ///< start of the x, y and z rows
  const int* slot;  ///< position of each of the model columns in the rows
};

/// Width of the batched kernel: one sample per lane (lanes::kLanes).
inline constexpr int kJacobianLanes = lanes::kLanes;

/// For kJacobianLanes samples at once, lane k computing exactly what a single sample would
/// (element-wise IEEE operations, the same bits): writes sample k's d(tool point)/d(model
/// parameters) to target[k] and its tool point in the robot base frame to point_m[k] [m].
void tool_point_jacobian_rows(const RobotModel& model, const ModelTrig& model_trig,
                              const JointTrig* const (&joint_trig)[kJacobianLanes],
                              const JacobianRowsTarget (&target)[kJacobianLanes], Vec3 (&point_m)[kJacobianLanes]);

#ifdef HIVECAL_WIDE_LANES
/// Width of the AVX2 kernel (lanes::kWideLanes samples at once).
inline constexpr int kWideJacobianLanes = lanes::kWideLanes;
/// tool_point_jacobian_rows on 4-double lanes: call only when lanes::wide_lanes_available().
/// The same bits per sample.
void tool_point_jacobian_rows_wide(const RobotModel& model, const ModelTrig& model_trig,
                                   const JointTrig* const (&joint_trig)[kWideJacobianLanes],
                                   const JacobianRowsTarget (&target)[kWideJacobianLanes],
                                   Vec3 (&point_m)[kWideJacobianLanes]);
#endif

}  // namespace hivecal::detail
