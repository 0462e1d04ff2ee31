#include "hivecal/model/full_params.hpp"

#include <cmath>

#include "hivecal/core/math.hpp"
#include "core/names.hpp"

namespace hivecal {
namespace {

/// "theta<j>", "d<j>", "a<j>", "alpha<j>" of every joint the build holds, joint-major.
struct DhNames {
  detail::Name name[kMaxJoints * kParamsPerJoint];
};
constexpr DhNames dh_names() {
  DhNames names;
  for (int j = 0; j < kMaxJoints; ++j) {
    names.name[model_param_index(j, DhField::theta_offset)] = detail::numbered_name("theta", j + 1);
    names.name[model_param_index(j, DhField::d)] = detail::numbered_name("d", j + 1);
    names.name[model_param_index(j, DhField::a)] = detail::numbered_name("a", j + 1);
    names.name[model_param_index(j, DhField::alpha)] = detail::numbered_name("alpha", j + 1);
  }
  return names;
}
constexpr DhNames kDhNames = dh_names();

/// "compliance1" .. of every joint term the build holds.
struct TermNumberNames {
  detail::Name name[kMaxComplianceTerms];
};
constexpr TermNumberNames term_number_names() {
  TermNumberNames names;
  for (int t = 0; t < kMaxComplianceTerms; ++t) names.name[t] = detail::numbered_name("compliance", t + 1);
  return names;
}
constexpr TermNumberNames kTermNumberNames = term_number_names();

/// The tool point's, then the base's six parameters, in index order.
constexpr const char* kToolAndBaseNames[kToolParamCount + kBaseParamCount] = {
    "tool_x", "tool_y", "tool_z", "base_rx", "base_ry", "base_rz", "base_tx", "base_ty", "base_tz"};

constexpr const char* kOtherToolNames[kMaxTargets - 1][3] = {{"tool2_x", "tool2_y", "tool2_z"},
                                                             {"tool3_x", "tool3_y", "tool3_z"}};
static_assert(kMaxTargets == 3, "one name row per target 2 ..");

}  // namespace

const char* other_tool_param_name(int target, int axis) {
  if (target < 1 || target >= kMaxTargets || axis < 0 || axis >= 3) return "?";
  return kOtherToolNames[target - 1][axis];
}

int mask_count(ParamMask mask) {
  int count = 0;
  for (int i = 0; i < kFullParamCount; ++i) count += mask_has(mask, i) ? 1 : 0;
  return count;
}

int mask_indices(ParamMask mask, int (&index)[kFullParamCount]) {
  int count = 0;
  for (int i = 0; i < kFullParamCount; ++i) {
    if (mask_has(mask, i)) index[count++] = i;
  }
  return count;
}

ParamMask harmonic_params_mask(const RobotModel& model) {
  ParamMask mask = 0;
  for (int t = 0; t < model.compliance.term_count; ++t) {
    if (is_harmonic(model.compliance.terms[t])) mask |= param_bit(compliance_param_index(model, t));
  }
  return mask;
}

const char* full_param_name(int index, int joint_count) {
  if (joint_count < 1 || joint_count > kMaxJoints || index < 0) return "?";
  const int dh_count = joint_count * kParamsPerJoint;
  if (index < dh_count) return kDhNames.name[index].text;
  const int rigid_count = rigid_param_count(joint_count);
  if (index < rigid_count) return kToolAndBaseNames[index - dh_count];
  if (index < rigid_count + kMaxComplianceTerms) return kTermNumberNames.name[index - rigid_count].text;
  return "?";
}

const char* full_param_name(int index, const RobotModel& model) {
  const int rigid_count = rigid_param_count(model);
  if (index < rigid_count || index >= rigid_count + kMaxComplianceTerms)
    return full_param_name(index, model.joint_count);
  return compliance_term_name(model.compliance, index - rigid_count);
}

Mat3 rotation_from_vector(const Vec3& rotation_vector_rad) {
  const double angle2 = rotation_vector_rad.squaredNorm();
  double sin_ratio = 1.0;  // sine of t over t (evaluated with math::sincos below)
  double cos_ratio = 0.5;  // (1 - cosine of t) / t^2 (math::sincos, not libm)
  if (angle2 < 1e-8) {     // t < 1e-4: Taylor terms beyond t^4 are below 1e-24
    sin_ratio = 1.0 - angle2 / 6.0 + angle2 * angle2 / 120.0;
    cos_ratio = 0.5 - angle2 / 24.0 + angle2 * angle2 / 720.0;
  } else {
    const double angle = std::sqrt(angle2);
    double s = 0.0;
    double c = 0.0;
    math::sincos(angle, &s, &c);
    sin_ratio = s / angle;
    cos_ratio = (1.0 - c) / angle2;
  }
  const Mat3 k = skew(rotation_vector_rad);
  return Mat3::Identity() + sin_ratio * k + cos_ratio * (k * k);
}

void apply_full_increment(const FullParams& increment, RobotModel* model, RigidTransform* base_to_tracker) {
  // The geometry entries of the increment are laid out as ModelParams for the model's joint
  // count (the entries after them, the base's and the terms', are not read back).
  set_model_params(to_params(*model) + increment.head<kMaxModelParamCount>(), model);
  for (int t = 0; t < model->compliance.term_count; ++t) {
    model->compliance.coefficient[t] += increment(compliance_param_index(*model, t));
  }
  const Vec3 rotation_rad = increment.segment<3>(base_rotation_param_index(*model, 0));
  const Vec3 translation_m = increment.segment<3>(base_translation_param_index(*model, 0));
  base_to_tracker->translation_m += base_to_tracker->rotation * translation_m;
  base_to_tracker->rotation = base_to_tracker->rotation * rotation_from_vector(rotation_rad);
}

double full_param_value(const RobotModel& model, int index) {
  const int rigid = rigid_param_count(model);
  if (index >= rigid) return model.compliance.coefficient[index - rigid];
  return index < model_param_count(model) ? model_param(model, index) : 0.0;
}

}  // namespace hivecal
