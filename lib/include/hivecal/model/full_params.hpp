// The full calibration model's parameters: the 27 geometry parameters of kinematics.hpp, the
// robot base -> tracker transform (33: the rigid model) and the coefficients of the model's
// joint terms (model/compliance.hpp: gravity compliance and joint-angle harmonics, as many as
// the build's capacity holds: 37 or 73 in all); their indices, masks, names and how an
// increment applies.
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

inline constexpr int kBaseParamCount = 6;                                       ///< rotation (3) + translation (3)
inline constexpr int kRigidParamCount = kModelParamCount + kBaseParamCount;     ///< 33: geometry and base
inline constexpr int kFullParamCount = kRigidParamCount + kMaxComplianceTerms;  ///< 37 or 73: and the joint terms

/// Index of the base rotation increment about base axis `axis` (0 = x, 1 = y, 2 = z).
constexpr int base_rotation_param_index(int axis) {
  return kModelParamCount + axis;
}
/// Index of the base translation increment along base axis `axis` (0 = x, 1 = y, 2 = z).
constexpr int base_translation_param_index(int axis) {
  return kModelParamCount + 3 + axis;
}
/// Index of the coefficient of compliance term `term` (0 .. kMaxComplianceTerms - 1).
constexpr int compliance_param_index(int term) {
  return kRigidParamCount + term;
}

/// One value per full-model parameter (an increment, a sigma, ...) [m] or [rad].
using FullParams = Eigen::Matrix<double, kFullParamCount, 1>;
/// d(residual of one sample) / d(full parameters) [m/m] or [m/rad].
using FullJacobian = Eigen::Matrix<double, 3, kFullParamCount>;

/// A set of full-model parameters: bit i stands for parameter i, and one bit more
/// (kOtherTargetTools). One word while the parameters and that bit fit in 64 bits (up to 30
/// joint terms: the bare-metal build), two words beyond (the hosted builds' 40).
using ParamMask = std::conditional_t<kFullParamCount + 1 <= 64, std::uint64_t, WideMask>;
/// The mask holding only parameter `index`.
constexpr ParamMask param_bit(int index) {
  return ParamMask{1} << static_cast<unsigned>(index);
}
/// Every parameter of the rigid model (the 33 geometry and base parameters); LmParamSet::full.
inline constexpr ParamMask kAllParamsMask = (ParamMask{1} << kRigidParamCount) - 1U;
/// The coefficients of the kMaxComplianceTerms compliance terms (which exist: term_count).
inline constexpr ParamMask kComplianceParamsMask = ((ParamMask{1} << kFullParamCount) - 1U) & ~kAllParamsMask;
/// The coefficients of the first `term_count` compliance terms.
constexpr ParamMask compliance_params_mask(int term_count) {
  return ((ParamMask{1} << static_cast<unsigned>(kRigidParamCount + term_count)) - 1U) & ~kAllParamsMask;
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
/// Every valid parameter bit: the rigid ones and the compliance coefficients.
inline constexpr ParamMask kValidParamsMask = kAllParamsMask | kComplianceParamsMask;
/// Number of parameters in `mask`.
int mask_count(ParamMask mask);
/// The parameters of `mask` in increasing order into index[0 .. count-1]; returns count.
int mask_indices(ParamMask mask, int (&index)[kFullParamCount]);

/// Short name of a full-model parameter: "theta1", "d2", "a3", "alpha4", "tool_x",
/// "base_rz", "base_tx", ..., "compliance1" .. "compliance4"; "?" outside [0,
/// kFullParamCount). Static storage.
const char* full_param_name(int index);
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

/// Adds a full-model increment: the 27 model entries add to the model, the compliance ones to
/// the coefficients of its terms (its other fields are kept), the base ones compose as
/// base <- base * (Exp(rotation), translation).
void apply_full_increment(const FullParams& increment, RobotModel* model, RigidTransform* base_to_tracker);

}  // namespace hivecal
