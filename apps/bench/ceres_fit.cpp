#include "ceres_fit.hpp"

#include "hivecal/model/kinematics.hpp"

namespace ceres_fit {

using hivecal::kSixJoints;

static_assert(ceres_peer::kJoints == kSixJoints && ceres_peer::kDhParams == kSixJoints * hivecal::kParamsPerJoint,
              "ceres_peer mirrors the model layout of a six-joint arm");
static_assert(ceres_peer::kParams == hivecal::rigid_param_count(kSixJoints), "same parameter vector (the rigid 33)");

void prepare(const hivecal::RobotModel& start, const hivecal::RigidTransform& start_base,
             hivecal::Span<const hivecal::Sample> samples, hivecal::ParamMask estimated, Input* in) {
  in->q_rad.clear();
  in->point_m.clear();
  for (const hivecal::Sample& s : samples) {
    for (int j = 0; j < kSixJoints; ++j) in->q_rad.push_back(s.q_rad(j));
    for (int i = 0; i < 3; ++i) in->point_m.push_back(s.point_m(i));
  }
  ceres_peer::Problem& p = in->problem;
  p.q_rad = in->q_rad.data();
  p.point_m = in->point_m.data();
  p.count = samples.size();
  for (int i = 0; i < 3; ++i) {
    p.base_translation_m[i] = start_base.translation_m(i);
    for (int k = 0; k < 3; ++k) p.base_rotation[3 * i + k] = start_base.rotation(i, k);
  }
  const hivecal::ModelParams start_params = hivecal::to_params(start);
  for (int i = 0; i < hivecal::model_param_count(kSixJoints); ++i) p.start[i] = start_params(i);
  for (int i = 0; i < ceres_peer::kParams; ++i) p.fixed[i] = !hivecal::mask_has(estimated, i);
}

Outcome solve(const hivecal::RigidTransform& start_base, const Input& in, bool verbose) {
  const ceres_peer::Outcome solved = ceres_peer::solve(in.problem, verbose);
  Outcome out;
  out.usable = solved.usable;
  out.iterations = solved.iterations;
  hivecal::ModelParams params = hivecal::ModelParams::Zero();
  for (int i = 0; i < hivecal::model_param_count(kSixJoints); ++i) params(i) = solved.params[i];
  out.model = hivecal::RobotModel{};  // a six-joint arm, as the peer's
  hivecal::set_model_params(params, &out.model);
  const double* rotation = solved.params + hivecal::base_rotation_param_index(kSixJoints, 0);
  const double* translation = solved.params + hivecal::base_translation_param_index(kSixJoints, 0);
  out.base.rotation =
      start_base.rotation * hivecal::rotation_from_vector(hivecal::Vec3(rotation[0], rotation[1], rotation[2]));
  out.base.translation_m =
      start_base.translation_m + start_base.rotation * hivecal::Vec3(translation[0], translation[1], translation[2]);
  return out;
}

}  // namespace ceres_fit
