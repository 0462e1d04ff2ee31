// The full calibration model's parameters: the geometry parameters of kinematics.hpp (4 per
// joint and the tool point), the robot base -> tracker transform (the rigid model: 33 for six
// joints) and the coefficients of the model's joint terms (model/compliance.hpp: gravity
// compliance and joint-angle harmonics); their indices, masks, names and how an increment
// applies. The indices depend on the model's joint count: a model of n joints has its 4 n DH
// parameters first, then the tool, the base and the joint terms, so a six-joint model's indices
// are the same in every build. The vectors and masks have room for the build's capacity
// (kFullParamCount: kMaxJoints and kMaxJointTerms).
//
// The base is not stored as parameters: it is a RigidTransform, and its six parameters are
// a local increment (rotation vector, translation) expressed in the robot base frame,
//   base <- base * (Exp(rotation_increment), translation_increment),
// so that base_rz and base_tz move the robot exactly as theta1 and d1 do.
#pragma once

#include <cstdint>
#include <type_traits>

#include <Eigen/Core>

#include "hivecal/core/types.hpp"
#include "hivecal/core/wide_mask.hpp"
#include "hivecal/model/kinematics.hpp"

namespace hivecal {

inline constexpr int kBaseParamCount = 6;  ///< rotation (3) + translation (3)
/// Rigid parameters of a model of `joint_count` joints: its geometry and the base (33 for six).
constexpr int rigid_param_count(int joint_count) {
  return model_param_count(joint_count) + kBaseParamCount;
}
/// Rigid parameters of the largest model the build holds [-].
inline constexpr int kMaxRigidParamCount = rigid_param_count(kMaxJoints);
/// Room for every parameter of any model the build holds: its rigid ones and the joint terms
/// (37 for six joints and 4 terms, 81 for eight and 40) [-].
inline constexpr int kFullParamCount = kMaxRigidParamCount + kMaxComplianceTerms;

/// Index of the base rotation increment about base axis `axis` (0 = x, 1 = y, 2 = z) of a model
/// of `joint_count` joints.
constexpr int base_rotation_param_index(int joint_count, int axis) {
  return model_param_count(joint_count) + axis;
}
/// Index of the base translation increment along base axis `axis` (0 = x, 1 = y, 2 = z).
constexpr int base_translation_param_index(int joint_count, int axis) {
  return model_param_count(joint_count) + 3 + axis;
}
/// Index of the coefficient of compliance term `term` (0 .. kMaxComplianceTerms - 1).
constexpr int compliance_param_index(int joint_count, int term) {
  return rigid_param_count(joint_count) + term;
}
/// Rigid parameters of `model` [-].
inline int rigid_param_count(const RobotModel& model) {
  return rigid_param_count(model.joint_count);
}
/// base_rotation_param_index of `model`'s joint count.
inline int base_rotation_param_index(const RobotModel& model, int axis) {
  return base_rotation_param_index(model.joint_count, axis);
}
/// base_translation_param_index of `model`'s joint count.
inline int base_translation_param_index(const RobotModel& model, int axis) {
  return base_translation_param_index(model.joint_count, axis);
}
/// compliance_param_index of `model`'s joint count.
inline int compliance_param_index(const RobotModel& model, int term) {
  return compliance_param_index(model.joint_count, term);
}

/// One value per full-model parameter (an increment, a sigma, ...) [m] or [rad].
using FullParams = Eigen::Matrix<double, kFullParamCount, 1>;
/// d(residual of one sample) / d(full parameters) [m/m] or [m/rad].
using FullJacobian = Eigen::Matrix<double, 3, kFullParamCount>;

/// A set of full-model parameters: bit i stands for parameter i, and one bit more
/// (kOtherTargetTools). One word while the parameters and that bit fit in 64 bits (the
/// bare-metal build), two words beyond (the hosted builds').
using ParamMask = std::conditional_t<kFullParamCount + 1 <= 64, std::uint64_t, WideMask>;
static_assert(kFullParamCount + 1 <= 128, "every parameter and the other targets' flag fit in a mask");
/// The mask holding only parameter `index`.
constexpr ParamMask param_bit(int index) {
  return ParamMask{1} << static_cast<unsigned>(index);
}
/// Every rigid parameter of a model of `joint_count` joints (geometry and base); LmParamSet::full.
constexpr ParamMask rigid_params_mask(int joint_count) {
  return (ParamMask{1} << static_cast<unsigned>(rigid_param_count(joint_count))) - 1U;
}
/// The coefficients of the first `term_count` compliance terms of a model of `joint_count` joints.
constexpr ParamMask compliance_params_mask(int joint_count, int term_count) {
  return ((ParamMask{1} << static_cast<unsigned>(rigid_param_count(joint_count) + term_count)) - 1U) &
         ~rigid_params_mask(joint_count);
}
/// Every parameter a model of `joint_count` joints can have: its rigid ones and the
/// kMaxComplianceTerms term coefficients.
constexpr ParamMask valid_params_mask(int joint_count) {
  return rigid_params_mask(joint_count) | compliance_params_mask(joint_count, kMaxComplianceTerms);
}
/// rigid_params_mask of `model`'s joint count.
inline ParamMask rigid_params_mask(const RobotModel& model) {
  return rigid_params_mask(model.joint_count);
}
/// valid_params_mask of `model`'s joint count.
inline ParamMask valid_params_mask(const RobotModel& model) {
  return valid_params_mask(model.joint_count);
}
/// The coefficients of `model`'s compliance terms (its term_count).
inline ParamMask compliance_params_mask(const RobotModel& model) {
  return compliance_params_mask(model.joint_count, model.compliance.term_count);
}
/// The coefficients of `model`'s harmonic terms (compliance.hpp), among its first term_count.
ParamMask harmonic_params_mask(const RobotModel& model);
/// Not a parameter: in a mask of columns to sum (accumulate_normal_equations), the tool points
/// of targets 2 .. kMaxTargets are estimated too (mask_count and mask_indices ignore it).
inline constexpr ParamMask kOtherTargetTools = ParamMask{1} << kFullParamCount;
/// True when parameter `index` is in `mask`.
constexpr bool mask_has(ParamMask mask, int index) {
  return (mask & param_bit(index)) != 0;
}
/// Number of parameters in `mask`.
int mask_count(ParamMask mask);
/// The parameters of `mask` in increasing order into index[0 .. count-1]; returns count.
int mask_indices(ParamMask mask, int (&index)[kFullParamCount]);

/// Short name of parameter `index` of a model of `joint_count` joints: "theta1", "d2", "a3",
/// "alpha4", ..., "tool_x", "base_rz", "base_tx", ..., "compliance1", "compliance2", ...; "?"
/// outside its valid_params_mask. Static storage.
const char* full_param_name(int index, int joint_count);
/// The same with the compliance coefficients named after `model`'s terms ("c_j2_o2", ...,
/// compliance_term_name; "?" beyond its term_count). Static storage.
const char* full_param_name(int index, const RobotModel& model);

/// Name of coordinate `axis` (0 = x) of the tool point of target `target` (0-based, 1 ..
/// kMaxTargets - 1; not among the kFullParamCount): "tool2_x", ...; "?" outside. Static storage.
const char* other_tool_param_name(int target, int axis);

/// Cross-product matrix: skew(v) * x = v x x.
inline Mat3 skew(const Vec3& v) {
  Mat3 k;
  k << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return k;
}

/// Rotation matrix of a rotation vector [rad] (Rodrigues' formula, own sincos).
Mat3 rotation_from_vector(const Vec3& rotation_vector_rad);

/// Adds a full-model increment: the model_param_count geometry entries add to the model, the
/// compliance ones to the coefficients of its terms (its other fields are kept), the base ones
/// compose as base <- base * (Exp(rotation), translation).
void apply_full_increment(const FullParams& increment, RobotModel* model, RigidTransform* base_to_tracker);

/// The value of full-model parameter `index` in `model`: a geometry parameter (model_param) or a
/// joint term's coefficient; 0 for the base's six (held as an increment, not a value).
double full_param_value(const RobotModel& model, int index);

}  // namespace hivecal
