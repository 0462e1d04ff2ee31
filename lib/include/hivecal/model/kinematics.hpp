// Denavit-Hartenberg model of a serial arm of 1 .. kMaxJoints revolute or prismatic joints plus
// a tool point, its forward kinematics and the analytic Jacobian of the tool point with respect
// to the geometry.
//
// Convention (docs/kinematics.md): T_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i) with
// theta_i = q_i + theta_offset_i and d_i = d_i for a revolute joint, theta_i = theta_offset_i
// and d_i = q_i + d_i for a prismatic one; flange = T_1 ... T_n, tool point = flange * [tool_m, 1].
#pragma once

#include <cstdint>

#include <Eigen/Core>

#include "hivecal/core/joints.hpp"
#include "hivecal/core/status.hpp"
#include "hivecal/core/types.hpp"
#include "hivecal/model/compliance.hpp"

namespace hivecal {

inline constexpr int kParamsPerJoint = 4;  ///< theta_offset, d, a, alpha
inline constexpr int kToolParamCount = 3;  ///< tool x, y, z
inline constexpr int kMaxModelParamCount = kMaxJoints * kParamsPerJoint + kToolParamCount;  ///< 27 for six joints
/// Reflectors (targets) one calibration can hold on the tool, each with its own tool point
/// (3: a fourth costs 1.8 kB of LmWorkspace, and the 512-sample firmware job has < 1 kB left).
inline constexpr int kMaxTargets = 3;

/// Position of a DH field inside a joint's four parameters.
enum class DhField : int { theta_offset = 0, d = 1, a = 2, alpha = 3 };

/// Index of joint `joint` (0-based) field `field` in a ModelParams vector (joint-major, the
/// same for every joint count).
constexpr int model_param_index(int joint, DhField field) {
  return joint * kParamsPerJoint + static_cast<int>(field);
}
/// Geometry parameters of a model of `joint_count` joints: its DH fields, then the tool point
/// (27 for six joints) [-].
constexpr int model_param_count(int joint_count) {
  return joint_count * kParamsPerJoint + kToolParamCount;
}
/// Index of tool coordinate `axis` (0 = x, 1 = y, 2 = z) in the ModelParams of a model of
/// `joint_count` joints: after its DH fields.
constexpr int tool_param_index(int joint_count, int axis) {
  return joint_count * kParamsPerJoint + axis;
}
/// True when geometry parameter `index` of a model of `joint_count` joints is an angle (a
/// theta offset or an alpha [rad]); the d, a and the tool point are lengths [m].
constexpr bool model_param_is_angle(int index, int joint_count) {
  const int field = index % kParamsPerJoint;
  return index >= 0 && index < joint_count * kParamsPerJoint &&
         (field == static_cast<int>(DhField::theta_offset) || field == static_cast<int>(DhField::alpha));
}

/// One joint's DH parameters.
struct DhJoint {
  double theta_offset_rad =
      0.0;                 ///< added to the reading of a revolute joint; the fixed theta of a prismatic one [rad]
  double d_m = 0.0;        ///< offset along the previous z; added to the reading of a prismatic joint [m]
  double a_m = 0.0;        ///< length along x of the next frame [m]
  double alpha_rad = 0.0;  ///< twist about x of the next frame [rad]
};

/// The geometry the calibration estimates: the DH joints, the tool point of each target and
/// the joints' compliance (none by default: a rigid arm). Built by default as a six-joint
/// revolute arm (all zeros); joint_count and the joint types say what the arm is. Laid out without
/// padding, so that whole models compare byte for byte.
struct RobotModel {
  DhJoint joints[kMaxJoints];  ///< joint 1 (base) .. joint joint_count; the rest unused (zero)
  Vec3 tool_m = Vec3::Zero();  ///< tool point of target 1 (retroreflector centre) in the flange frame [m]
  /// Tool points of targets 2 .. kMaxTargets in the flange frame [m]; not among the model parameters.
  Vec3 other_tools_m[kMaxTargets - 1] = {Vec3::Zero(), Vec3::Zero()};
  /// Gravity deflection of the joints (model/compliance.hpp); not among the model parameters.
  ComplianceModel compliance;
  /// Bit j set: joint j + 1 is prismatic (JointType::prismatic), else revolute (joint_type()).
  std::uint32_t prismatic_joints = 0;
  int joint_count = kSixJoints;  ///< joints of the arm, 1 .. kMaxJoints [-]
};
static_assert(kMaxTargets == 3, "other_tools_m's initialiser lists kMaxTargets - 1 points");
static_assert(kMaxJoints <= 32, "prismatic_joints has a bit per joint");

/// The type of joint `joint` (0-based) of `model`.
inline JointType joint_type(const RobotModel& model, int joint) {
  return (model.prismatic_joints >> static_cast<unsigned>(joint) & 1U) != 0 ? JointType::prismatic
                                                                            : JointType::revolute;
}
/// Sets the type of joint `joint` (0-based) of *model.
inline void set_joint_type(RobotModel* model, int joint, JointType type) {
  const std::uint32_t bit = std::uint32_t{1} << static_cast<unsigned>(joint);
  model->prismatic_joints =
      type == JointType::prismatic ? model->prismatic_joints | bit : model->prismatic_joints & ~bit;
}
/// The joints of `model`: joint_count of them (for range loops).
inline Span<const DhJoint> model_joints(const RobotModel& model) {
  return Span<const DhJoint>(model.joints, static_cast<std::size_t>(model.joint_count));
}
/// The same, writable.
inline Span<DhJoint> model_joints(RobotModel* model) {
  return Span<DhJoint>(model->joints, static_cast<std::size_t>(model->joint_count));
}
/// True when every joint of `model` is revolute.
inline bool all_revolute(const RobotModel& model) {
  return model.prismatic_joints == 0;
}

/// Geometry parameters of `model` (model_param_count of its joint count) [-].
inline int model_param_count(const RobotModel& model) {
  return model_param_count(model.joint_count);
}
/// Index of tool coordinate `axis` in `model`'s ModelParams.
inline int tool_param_index(const RobotModel& model, int axis) {
  return tool_param_index(model.joint_count, axis);
}

/// Status::ok when `model`'s shape is one the library models: joint_count in [1, kMaxJoints],
/// only those joints prismatic, the unused joints zero; invalid_argument otherwise.
Status check_joint_layout(const RobotModel& model);

/// Tool point of target `target` (0-based, < kMaxTargets) in the flange frame [m].
inline const Vec3& target_tool(const RobotModel& model, int target) {
  return target == 0 ? model.tool_m : model.other_tools_m[target - 1];
}
/// The same, writable.
inline Vec3& target_tool(RobotModel* model, int target) {
  return target == 0 ? model->tool_m : model->other_tools_m[target - 1];
}

/// A model's geometry parameters as one vector: joint-major DH fields, then the tool
/// (model_param_count of them; zeros after).
using ModelParams = Eigen::Matrix<double, kMaxModelParamCount, 1>;
/// d(tool point in base frame) / d(ModelParams), [m/m] or [m/rad] (zero beyond the model's columns).
using ToolPointJacobian = Eigen::Matrix<double, 3, kMaxModelParamCount>;

/// Flattens a model into its parameter vector.
ModelParams to_params(const RobotModel& model);
/// Geometry parameter `index` (in [0, model_param_count(model))) of `model`: to_params(model)(index)
/// without the vector (a caller's stack on the firmware) [m] or [rad].
double model_param(const RobotModel& model, int index);
/// Writes the geometry parameters into *model in place (as many as its joint count has); its
/// joint count and types, its other targets' tool points and its compliance, which are not
/// among them, stay as they are.
void set_model_params(const ModelParams& params, RobotModel* model);
/// `model` with its geometry parameters replaced by `params` (set_model_params on a copy).
inline RobotModel with_model_params(const RobotModel& model, const ModelParams& params) {
  RobotModel out = model;
  set_model_params(params, &out);
  return out;
}

/// Robot types with built-in nominal tables: Universal Robots' six-axis arms and, in builds whose
/// models hold seven joints (HIVECAL_MAX_JOINTS >= 7: the hosted ones), seven-axis arms from their
/// makers' published tables (a six-joint build has no such type).
enum class RobotType : int {
  ur3,
  ur5,
  ur10,
  ur5e,
  ur3e,
  ur10e,
  ur16e,
#if HIVECAL_MAX_JOINTS >= 7
  iiwa14,  ///< KUKA LBR iiwa 14 R820
  panda,   ///< Franka Emika Robot (Panda)
  fr3,     ///< Franka Research 3: the Panda's kinematics, its own joint limits
  gen3,    ///< Kinova Gen3 with 7 DoF (spherical wrist)
  wam,     ///< Barrett WAM with 7 DoF
#endif
};

/// The built-in types in the order robot_type_names() lists them (UR's first).
Span<const RobotType> builtin_robot_types();
/// Nominal (published) geometry of a robot type: its joint count, each joint revolute, and the
/// tool point at the maker's flange. A table the maker writes in modified DH, or with a fixed
/// rotation before joint 1, comes as its standard-DH chain; nominal_convention
/// (model/dh_convention.hpp) gives the convention and the base offset in front of it.
RobotModel nominal_model(RobotType type);
/// The names robot_type_from_name accepts, for messages: "ur3, ur5, ur10, ur3e, ur5e, ur10e,
/// ur16e" and, in a build of seven joints or more, ", iiwa14, panda, fr3, gen3, wam".
const char* robot_type_names();
/// Lower-case name of a robot type ("ur5").
const char* robot_type_name(RobotType type);
/// Parses a name of robot_type_names() ("ur3", "ur5", "ur10" (CB3), "ur3e", "ur5e", "ur10e",
/// "ur16e" (e-Series), "iiwa14", ...); Status::invalid_argument otherwise.
Status robot_type_from_name(const char* name, RobotType* type);
/// The maker's position limits of each joint of a built-in seven-axis type ([rad]; an endless
/// joint +-2 pi, as are the entries beyond its joints): Status::ok, or invalid_argument for a UR
/// type, whose joints turn +-360 deg (plan/pose_plan.hpp's default_joint_limits says how
/// planning keeps them).
Status maker_joint_limits(RobotType type, JointVector* lower_rad, JointVector* upper_rad);

/// The FK functions below apply the model's compliance when it has terms: the rigid chain at
/// q + compliance_deflection(model, q), the same deflection for every target (its load is
/// target 1's tool point). Without terms they are the rigid chain, bit for bit.

/// Pose of the flange frame in the robot base frame.
RigidTransform fk_flange(const RobotModel& model, const JointVector& q_rad);
/// Tool point in the robot base frame [m]; cheaper than fk_flange (vector recursion only).
Vec3 fk_tool_point(const RobotModel& model, const JointVector& q_rad);
/// Point of target `target` (0-based) in the robot base frame [m]; target 0 is fk_tool_point.
Vec3 fk_target_point(const RobotModel& model, const JointVector& q_rad, int target);
/// Tool point [m] and, into *jacobian, its analytic derivative w.r.t. the model's parameters
/// (model_param_count columns; the rest 0). The joint angles enter as sin/cos(q_j + offset_j)
/// by the angle-sum formulas from JointTrig and ModelTrig (so that solvers can keep the
/// JointTrig of their samples); the point agrees with fk_tool_point to rounding. With
/// compliance: the rigid derivative at the deflected pose.
Vec3 tool_point_jacobian(const RobotModel& model, const JointVector& q_rad, ToolPointJacobian* jacobian);

/// sin and cos of each joint's twist and offset: they do not depend on the pose, so loops
/// over many samples of one model compute them once.
struct ModelTrig {
  double sin_alpha[kMaxJoints] = {};   ///< sine of alpha_j, from math::sincos [-]
  double cos_alpha[kMaxJoints] = {};   ///< cosine of alpha_j, from math::sincos [-]
  double sin_offset[kMaxJoints] = {};  ///< sine of theta_offset_j, from math::sincos [-]
  double cos_offset[kMaxJoints] = {};  ///< cosine of theta_offset_j, from math::sincos [-]
};
/// The trig of `model`.
ModelTrig model_trig(const RobotModel& model);
/// fk_tool_point with the trig of `model` precomputed (same bits; reads the twist half only).
Vec3 fk_tool_point(const RobotModel& model, const ModelTrig& trig, const JointVector& q_rad);
/// fk_target_point with the trig of `model` precomputed (same bits).
Vec3 fk_target_point(const RobotModel& model, const ModelTrig& trig, const JointVector& q_rad, int target);

/// sin and cos of one pose's joint readings, without the offsets: they depend on the model's
/// joint types only, so a solver that visits the samples many times can compute them once per
/// sample. A prismatic joint does not turn (sin 0, cos 1: theta is its offset alone); its
/// reading is a slide along z instead.
struct JointTrig {
  double sin_q[kMaxJoints] = {};    ///< sine of q_j (revolute), 0 (prismatic), from math::sincos [-]
  double cos_q[kMaxJoints] = {};    ///< cosine of q_j (revolute), 1 (prismatic), from math::sincos [-]
  double slide_m[kMaxJoints] = {};  ///< q_j of a prismatic joint, 0 of a revolute one [m]
};
/// The joint trig of a pose of `model` (its joint count and types).
JointTrig joint_trig(const RobotModel& model, const JointVector& q_rad);

}  // namespace hivecal
