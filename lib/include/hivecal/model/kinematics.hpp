// Standard Denavit-Hartenberg model of a 6-joint arm plus a tool point, its forward
// kinematics and the analytic Jacobian of the tool point with respect to the geometry.
//
// Convention (docs/kinematics.md): T_i = Rz(q_i + theta_offset_i) Tz(d_i) Tx(a_i) Rx(alpha_i),
// flange = T_1 ... T_6, tool point = flange * [tool_m, 1].
#pragma once

#include <Eigen/Core>

#include "hivecal/core/status.hpp"
#include "hivecal/core/types.hpp"
#include "hivecal/model/compliance.hpp"

namespace hivecal {

inline constexpr int kParamsPerJoint = 4;                                 ///< theta_offset, d, a, alpha
inline constexpr int kDhParamCount = kJointCount * kParamsPerJoint;       ///< 24
inline constexpr int kToolParamCount = 3;                                 ///< tool x, y, z
inline constexpr int kModelParamCount = kDhParamCount + kToolParamCount;  ///< 27
/// Reflectors (targets) one calibration can hold on the tool, each with its own tool point
/// (3: a fourth costs 1.8 kB of LmWorkspace, and the 512-sample firmware job has < 1 kB left).
inline constexpr int kMaxTargets = 3;

/// Position of a DH field inside a joint's four parameters.
enum class DhField : int { theta_offset = 0, d = 1, a = 2, alpha = 3 };

/// Index of joint `joint` (0-based) field `field` in a ModelParams vector.
constexpr int model_param_index(int joint, DhField field) {
  return joint * kParamsPerJoint + static_cast<int>(field);
}
/// Index of tool coordinate `axis` (0 = x, 1 = y, 2 = z) in a ModelParams vector.
constexpr int tool_param_index(int axis) {
  return kDhParamCount + axis;
}

/// One joint's standard DH parameters.
struct DhJoint {
  double theta_offset_rad = 0.0;  ///< added to the joint reading [rad]
  double d_m = 0.0;               ///< offset along the previous z [m]
  double a_m = 0.0;               ///< length along x of the next frame [m]
  double alpha_rad = 0.0;         ///< twist about x of the next frame [rad]
};

/// The geometry the calibration estimates: six DH joints, the tool point of each target and
/// the joints' compliance (none by default: a rigid arm).
struct RobotModel {
  DhJoint joints[kJointCount];  ///< joint 1 (base) .. joint 6 (wrist 3)
  Vec3 tool_m = Vec3::Zero();   ///< tool point of target 1 (retroreflector centre) in the flange frame [m]
  /// Tool points of targets 2 .. kMaxTargets in the flange frame [m]; not among the 27 parameters.
  Vec3 other_tools_m[kMaxTargets - 1] = {Vec3::Zero(), Vec3::Zero()};
  /// Gravity deflection of the joints (model/compliance.hpp); not among the 27 parameters.
  ComplianceModel compliance;
};
static_assert(kMaxTargets == 3, "other_tools_m's initialiser lists kMaxTargets - 1 points");

/// Tool point of target `target` (0-based, < kMaxTargets) in the flange frame [m].
inline const Vec3& target_tool(const RobotModel& model, int target) {
  return target == 0 ? model.tool_m : model.other_tools_m[target - 1];
}
/// The same, writable.
inline Vec3& target_tool(RobotModel* model, int target) {
  return target == 0 ? model->tool_m : model->other_tools_m[target - 1];
}

/// All 27 model parameters as one vector: joint-major DH fields, then the tool.
using ModelParams = Eigen::Matrix<double, kModelParamCount, 1>;
/// d(tool point in base frame) / d(ModelParams), [m/m] or [m/rad].
using ToolPointJacobian = Eigen::Matrix<double, 3, kModelParamCount>;

/// Flattens a model into its parameter vector.
ModelParams to_params(const RobotModel& model);
/// Rebuilds a model from its parameter vector (the tool points of targets 2.. at 0, rigid).
RobotModel from_params(const ModelParams& params);
/// Writes the 27 parameters into *model in place; its other targets' tool points and its
/// compliance, which are not among them, stay as they are.
void set_model_params(const ModelParams& params, RobotModel* model);

/// Robot types with built-in nominal tables.
enum class RobotType : int { ur3, ur5, ur10, ur5e, ur3e, ur10e, ur16e };

/// Nominal (datasheet) geometry of a robot type; the tool point is at the flange.
RobotModel nominal_model(RobotType type);
/// The names robot_type_from_name accepts, for messages: "ur3, ur5, ur10, ur3e, ur5e, ur10e, ur16e".
const char* robot_type_names();
/// Lower-case name of a robot type ("ur5").
const char* robot_type_name(RobotType type);
/// Parses "ur3", "ur5", "ur10" (CB3) or "ur3e", "ur5e", "ur10e", "ur16e" (e-Series);
/// Status::invalid_argument otherwise.
Status robot_type_from_name(const char* name, RobotType* type);

/// The FK functions below apply the model's compliance when it has terms: the rigid chain at
/// q + compliance_deflection(model, q), the same deflection for every target (its load is
/// target 1's tool point). Without terms they are the rigid chain, bit for bit.

/// Pose of the flange frame in the robot base frame.
RigidTransform fk_flange(const RobotModel& model, const JointVector& q_rad);
/// Tool point in the robot base frame [m]; cheaper than fk_flange (vector recursion only).
Vec3 fk_tool_point(const RobotModel& model, const JointVector& q_rad);
/// Point of target `target` (0-based) in the robot base frame [m]; target 0 is fk_tool_point.
Vec3 fk_target_point(const RobotModel& model, const JointVector& q_rad, int target);
/// Tool point [m] and, into *jacobian, its analytic derivative w.r.t. all 27 parameters. The
/// joint angles enter as sin/cos(q_j + offset_j) by the angle-sum formulas from JointTrig and
/// ModelTrig (so that solvers can keep the JointTrig of their samples); the point agrees with
/// fk_tool_point to rounding. With compliance: the rigid derivative at the deflected pose.
Vec3 tool_point_jacobian(const RobotModel& model, const JointVector& q_rad, ToolPointJacobian* jacobian);

/// sin and cos of each joint's twist and offset: they do not depend on the pose, so loops
/// over many samples of one model compute them once.
struct ModelTrig {
  double sin_alpha[kJointCount] = {};   ///< sine of alpha_j, from math::sincos [-]
  double cos_alpha[kJointCount] = {};   ///< cosine of alpha_j, from math::sincos [-]
  double sin_offset[kJointCount] = {};  ///< sine of theta_offset_j, from math::sincos [-]
  double cos_offset[kJointCount] = {};  ///< cosine of theta_offset_j, from math::sincos [-]
};
/// The trig of `model`.
ModelTrig model_trig(const RobotModel& model);
/// fk_tool_point with the trig of `model` precomputed (same bits; reads the twist half only).
Vec3 fk_tool_point(const RobotModel& model, const ModelTrig& trig, const JointVector& q_rad);
/// fk_target_point with the trig of `model` precomputed (same bits).
Vec3 fk_target_point(const RobotModel& model, const ModelTrig& trig, const JointVector& q_rad, int target);

/// sin and cos of one pose's joint readings, without the offsets: they do not depend on the
/// model, so a solver that visits the samples many times can compute them once per sample.
struct JointTrig {
  double sin_q[kJointCount] = {};  ///< sine of q_j, from math::sincos [-]
  double cos_q[kJointCount] = {};  ///< cosine of q_j, from math::sincos [-]
};
/// The joint trig of a pose.
JointTrig joint_trig(const JointVector& q_rad);

}  // namespace hivecal
