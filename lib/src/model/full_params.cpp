#include "hivecal/model/full_params.hpp"

#include <cmath>

#include "hivecal/core/math.hpp"

namespace hivecal {
namespace {

/// The rigid model's parameters, then the joint terms' generic names up to the largest capacity.
constexpr const char* kParamNames[kRigidParamCount + 40] = {
    "theta1",       "d1",           "a1",           "alpha1",       "theta2",       "d2",           "a2",
    "alpha2",       "theta3",       "d3",           "a3",           "alpha3",       "theta4",       "d4",
    "a4",           "alpha4",       "theta5",       "d5",           "a5",           "alpha5",       "theta6",
    "d6",           "a6",           "alpha6",       "tool_x",       "tool_y",       "tool_z",       "base_rx",
    "base_ry",      "base_rz",      "base_tx",      "base_ty",      "base_tz",      "compliance1",  "compliance2",
    "compliance3",  "compliance4",  "compliance5",  "compliance6",  "compliance7",  "compliance8",  "compliance9",
    "compliance10", "compliance11", "compliance12", "compliance13", "compliance14", "compliance15", "compliance16",
    "compliance17", "compliance18", "compliance19", "compliance20", "compliance21", "compliance22", "compliance23",
    "compliance24", "compliance25", "compliance26", "compliance27", "compliance28", "compliance29", "compliance30",
    "compliance31", "compliance32", "compliance33", "compliance34", "compliance35", "compliance36", "compliance37",
    "compliance38", "compliance39", "compliance40"};
static_assert(kMaxComplianceTerms <= 40, "one name per joint term");

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
    if (is_harmonic(model.compliance.terms[t])) mask |= param_bit(compliance_param_index(t));
  }
  return mask;
}

const char* full_param_name(int index) {
  if (index < 0 || index >= kFullParamCount) return "?";
  return kParamNames[index];
}

const char* full_param_name(int index, const RobotModel& model) {
  if (index < kRigidParamCount || index >= kFullParamCount) return full_param_name(index);
  return compliance_term_name(model.compliance, index - kRigidParamCount);
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
  set_model_params(to_params(*model) + increment.head<kModelParamCount>(), model);
  for (int t = 0; t < model->compliance.term_count; ++t) {
    model->compliance.coefficient[t] += increment(compliance_param_index(t));
  }
  const Vec3 rotation_rad = increment.segment<3>(base_rotation_param_index(0));
  const Vec3 translation_m = increment.segment<3>(base_translation_param_index(0));
  base_to_tracker->translation_m += base_to_tracker->rotation * translation_m;
  base_to_tracker->rotation = base_to_tracker->rotation * rotation_from_vector(rotation_rad);
}

}  // namespace hivecal
