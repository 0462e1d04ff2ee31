#include "hivecal/plan/inverse_kinematics.hpp"

#include <Eigen/Cholesky>

#include "hivecal/core/math.hpp"

namespace hivecal {
namespace {

using PoseError = Eigen::Matrix<double, 6, 1>;
/// d(pose error) / d(joints): one column per joint of the model (fixed capacity, no heap).
using PoseJacobian = Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, kMaxJoints>;
/// The damped normal matrix over the joints.
using JointNormal = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxJoints, kMaxJoints>;

/// Commanded minus reached: position [m], then the rotation vector of the remaining turn [rad].
PoseError pose_error(const RobotModel& model, const RigidTransform& target, const JointVector& q_rad) {
  const RigidTransform at = fk_flange(model, q_rad);
  PoseError e;
  e.head<3>() = target.translation_m - at.translation_m;
  e.tail<3>() = rotation_vector_of(target.rotation * at.rotation.transpose());
  return e;
}

/// Wraps each revolute joint by whole turns into its limits where it can; false when a joint
/// stays outside.
bool wrap_into_limits(const RobotModel& model, const JointLimits& limits, JointVector* q_rad) {
  constexpr double kTurn_rad = 2.0 * math::kPi;
  bool inside = true;
  for (int j = 0; j < model.joint_count; ++j) {
    double& q = (*q_rad)(j);
    const bool turns = joint_type(model, j) == JointType::revolute;
    while (turns && q > limits.upper_rad(j) && q - kTurn_rad >= limits.lower_rad(j)) q -= kTurn_rad;
    while (turns && q < limits.lower_rad(j) && q + kTurn_rad <= limits.upper_rad(j)) q += kTurn_rad;
    inside = inside && q >= limits.lower_rad(j) && q <= limits.upper_rad(j);
  }
  return inside;
}

bool options_valid(const InverseKinematicsOptions& o) {
  return o.starts > 0 && o.iterations > 0 && o.position_tolerance_m > 0.0 && o.angle_tolerance_rad > 0.0 &&
         o.damping >= 0.0 && math::is_finite(o.damping);
}

}  // namespace

Vec3 rotation_vector_of(const Mat3& r) {
  // sin(angle) * axis from the skew part, cos(angle) from the trace; atan2 of both keeps the
  // angle accurate at every size.
  const Vec3 sin_axis = 0.5 * Vec3(r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1));
  const double sin_angle = sin_axis.norm();
  const double cos_angle = 0.5 * (r.trace() - 1.0);
  const double angle = math::atan2(sin_angle, cos_angle);
  if (cos_angle >= 0.0) return sin_angle > 0.0 ? Vec3(sin_axis * (angle / sin_angle)) : Vec3::Zero();
  // Beyond a quarter turn the skew part shrinks towards a half turn; the symmetric part
  // (R + R^T) / 2 - cos(angle) I = (1 - cos(angle)) a a^T keeps the axis: its largest column,
  // signed as the skew part says (either sign at exactly a half turn).
  const Mat3 outer = 0.5 * (r + r.transpose()) - cos_angle * Mat3::Identity();
  int k = 0;
  for (int i = 1; i < 3; ++i) {
    if (outer(i, i) > outer(k, k)) k = i;
  }
  Vec3 axis = outer.col(k) / outer.col(k).norm();
  if (axis.dot(sin_axis) < 0.0) axis = -axis;
  return angle * axis;
}

Status solve_flange_pose(const RobotModel& model, const JointLimits& limits, const RigidTransform& target,
                         const InverseKinematicsOptions& options, Random* random, JointVector* q_out) {
  if (random == nullptr || q_out == nullptr || !options_valid(options)) return Status::invalid_argument;
  if (!target.translation_m.allFinite() || !target.rotation.allFinite()) return Status::non_finite_input;
  constexpr double kStep = 1e-7;  // numeric Jacobian's step [rad] or [m]
  const int joints = model.joint_count;
  for (int start = 0; start < options.starts; ++start) {
    JointVector q;
    for (int j = 0; j < joints; ++j) q(j) = random->uniform(limits.lower_rad(j), limits.upper_rad(j));
    for (int iteration = 0; iteration < options.iterations; ++iteration) {
      const PoseError e = pose_error(model, target, q);
      if (e.head<3>().norm() < options.position_tolerance_m && e.tail<3>().norm() < options.angle_tolerance_rad) {
        if (!wrap_into_limits(model, limits, &q)) break;  // this start's solution is outside: the next start
        *q_out = q;
        return Status::ok;
      }
      // A redundant arm (more than six joints) has many solutions: the damping picks the
      // smallest step towards one of them.
      PoseJacobian jacobian(6, joints);
      for (int j = 0; j < joints; ++j) {
        JointVector moved = q;
        moved(j) += kStep;
        jacobian.col(j) = (e - pose_error(model, target, moved)) / kStep;
      }
      const JointNormal normal =
          jacobian.transpose() * jacobian + options.damping * JointNormal::Identity(joints, joints);
      q.head(joints) += normal.ldlt().solve(jacobian.transpose() * e);
    }
  }
  return Status::not_converged;
}

}  // namespace hivecal
