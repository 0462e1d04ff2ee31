// Prediction sigma, the calibration's domain and extrapolation (solve/prediction_uncertainty.hpp).
#include "hivecal/solve/prediction_uncertainty.hpp"

#include <cmath>

#include "hivecal/core/math.hpp"
#include "hivecal/model/compliance.hpp"

namespace hivecal {

namespace {

/// prediction_sigma_m's sum, trace(J C J^T) + the other tool's variances [m^2], with the model's
/// trig in `context` (one per model: sample_rows_context) and the estimated parameters listed
/// in index[0 .. count - 1].
double prediction_variance_sum_m2(const RobotModel& model, SampleRowsContext& context,
                                  const RigidTransform& base_to_tracker, const JointVector& q_rad, int target,
                                  const NormalMatrix& covariance, ParamMask estimated, const int* index, int count,
                                  PredictionFrame frame, const Vec3& target_tool_sigma_m) {
  // The Jacobian in the base frame (sample_rows' rows): the tracker frame's is R times it, and
  // trace(J C J^T) does not see a rotation. Target 1's tool columns are 0 for another target.
  Sample sample;
  sample.q_rad = q_rad;
  sample.target = target;
  context.pose = nullptr;  // its joint trig is this pose's, not the last one's (it knows a pose by its address)
  FullJacobian jacobian;
  Mat3 tool_jacobian;
  double raw_squared_m2 = 0.0;
  (void)sample_rows(model, context, base_to_tracker, sample, PointLoss{}, estimated, &jacobian, &tool_jacobian,
                    &raw_squared_m2);
  if (frame == PredictionFrame::base)
    jacobian.middleCols<kBaseParamCount>(base_rotation_param_index(model, 0)).setZero();
  double variance_sum_m2 = target > 0 ? target_tool_sigma_m.squaredNorm() : 0.0;
  for (int r = 0; r < 3; ++r) {
    for (int a = 0; a < count; ++a) {
      double row_dot = 0.0;  // (C J_r^T)_a
      for (int b = 0; b < count; ++b) row_dot += covariance(index[a], index[b]) * jacobian(r, index[b]);
      variance_sum_m2 += jacobian(r, index[a]) * row_dot;
    }
  }
  return variance_sum_m2;
}

}  // namespace

double prediction_sigma_m(const RobotModel& model, const RigidTransform& base_to_tracker, const JointVector& q_rad,
                          int target, const NormalMatrix& covariance, ParamMask estimated, PredictionFrame frame,
                          const Vec3& target_tool_sigma_m) {
  SampleRowsContext context = sample_rows_context(model);
  int index[kFullParamCount];
  const int count = mask_indices(estimated, index);
  const double sum_m2 = prediction_variance_sum_m2(model, context, base_to_tracker, q_rad, target, covariance,
                                                   estimated, index, count, frame, target_tool_sigma_m);
  return std::sqrt(std::fmax(sum_m2, 0.0) / 3.0);
}

Status calibration_domain(const RobotModel& model, const RigidTransform& base_to_tracker, Span<const Sample> samples,
                          const NormalMatrix& covariance, ParamMask estimated,
                          const Vec3 (&other_tools_sigma_m)[kMaxTargets - 1], CalibrationDomain* domain) {
  if (domain == nullptr) return Status::invalid_argument;
  if (samples.empty()) return Status::dataset_empty;
  CalibrationDomain d;
  d.joint_min_rad = samples[0].q_rad;
  d.joint_max_rad = samples[0].q_rad;
  Vec3 axis_sum = Vec3::Zero();
  double variance_sum_m2 = 0.0;
  SampleRowsContext context = sample_rows_context(model);
  int index[kFullParamCount];
  const int count = mask_indices(estimated, index);
  std::size_t pose_total = 0;
  for (std::size_t begin = 0; begin < samples.size(); begin = pose_run_end(samples, begin)) ++pose_total;
  std::size_t sigma_poses = 0;  // the sigmas of pose k where k * kDomainSigmaPoses / pose_total steps on
  for (std::size_t begin = 0; begin < samples.size();) {
    const std::size_t end = pose_run_end(samples, begin);
    const Sample* pose = &samples[begin];  // its target 1 reading, else its first
    for (std::size_t k = begin; k < end; ++k)
      if (samples[k].target == 0 && pose->target != 0) pose = &samples[k];
    if (!all_finite(pose->q_rad)) return Status::non_finite_input;
    d.joint_min_rad = d.joint_min_rad.cwiseMin(pose->q_rad);
    d.joint_max_rad = d.joint_max_rad.cwiseMax(pose->q_rad);
    axis_sum += fk_flange(model, pose->q_rad).rotation.col(2);
    const std::size_t k = d.poses++;
    if (pose_total <= kDomainSigmaPoses ||
        (k * kDomainSigmaPoses) / pose_total != ((k + 1) * kDomainSigmaPoses) / pose_total) {
      const Vec3 tool_sigma_m = pose->target > 0 ? other_tools_sigma_m[pose->target - 1] : Vec3(Vec3::Zero());
      const double variance_m2 =
          std::fmax(prediction_variance_sum_m2(model, context, base_to_tracker, pose->q_rad, pose->target, covariance,
                                               estimated, index, count, PredictionFrame::tracker, tool_sigma_m),
                    0.0) /
          3.0;
      variance_sum_m2 += variance_m2;
      d.max_sigma_m = std::fmax(d.max_sigma_m, std::sqrt(variance_m2));
      ++sigma_poses;
    }
    begin = end;
  }
  if (!(axis_sum.norm() > 0.0) || !std::isfinite(variance_sum_m2)) return Status::non_finite_input;
  d.tool_axis_mean = axis_sum.normalized();
  double angle_squares = 0.0;
  for (std::size_t begin = 0; begin < samples.size(); begin = pose_run_end(samples, begin)) {
    const Vec3 axis = fk_flange(model, samples[begin].q_rad).rotation.col(2);
    const double angle_rad = math::atan2(axis.cross(d.tool_axis_mean).norm(), axis.dot(d.tool_axis_mean));
    d.tool_axis_spread_rad = std::fmax(d.tool_axis_spread_rad, angle_rad);
    angle_squares += angle_rad * angle_rad;
  }
  const double poses = static_cast<double>(d.poses);
  d.tool_axis_rms_rad = std::sqrt(angle_squares / poses);
  d.typical_sigma_m = std::sqrt(variance_sum_m2 / static_cast<double>(sigma_poses));
  d.term_joints = term_joint_mask(model, samples);
  *domain = d;
  return Status::ok;
}

unsigned term_joint_mask(const RobotModel& model, Span<const Sample> samples) {
  constexpr std::size_t kPoses = 16;  // spread over the samples
  constexpr double kTurn_rad = 0.1;
  const ComplianceModel& terms = model.compliance;
  unsigned mask = 0;
  bool gravity = false;
  for (int t = 0; t < terms.term_count; ++t) {
    if (terms.coefficient[t] == 0.0) continue;
    if (is_harmonic(terms.terms[t])) {
      mask |= 1U << static_cast<unsigned>(terms.terms[t].joint);
    } else {
      gravity = true;
    }
  }
  if (!gravity || samples.empty()) return mask;
  const std::size_t step = samples.size() > kPoses ? samples.size() / kPoses : 1;
  for (std::size_t k = 0; k < samples.size(); k += step) {
    double basis[kMaxComplianceTerms];
    compliance_basis(model, samples[k].q_rad, basis);
    for (int j = 0; j < model.joint_count; ++j) {
      JointVector turned = samples[k].q_rad;
      turned(j) += kTurn_rad;
      double turned_basis[kMaxComplianceTerms];
      compliance_basis(model, turned, turned_basis);
      for (int t = 0; t < terms.term_count; ++t) {
        const bool counts = terms.coefficient[t] != 0.0 && !is_harmonic(terms.terms[t]);
        const double scale = std::fmax(std::fabs(basis[t]), std::fabs(turned_basis[t]));
        if (counts && std::fabs(turned_basis[t] - basis[t]) > 1e-9 * scale) mask |= 1U << static_cast<unsigned>(j);
      }
    }
  }
  return mask;
}

Extrapolation extrapolation(const CalibrationDomain& domain, const RobotModel& model, const JointVector& q_rad,
                            double sigma_m) {
  Extrapolation e;
  e.sigma_beyond = domain.typical_sigma_m > 0.0 && sigma_m > domain.sigma_factor * domain.typical_sigma_m;
  if (domain.tool_axis_mean.squaredNorm() > 0.0) {
    const Vec3 axis = fk_flange(model, q_rad).rotation.col(2);
    e.tool_axis_angle_rad = math::atan2(axis.cross(domain.tool_axis_mean).norm(), axis.dot(domain.tool_axis_mean));
    e.tool_axis_beyond = e.tool_axis_angle_rad > domain.tool_axis_spread_rad + domain.tool_axis_margin_rad;
  }
  for (int j = 0; j < model.joint_count; ++j) {
    if ((domain.term_joints & (1U << static_cast<unsigned>(j))) == 0) continue;
    const double beyond_rad = std::fmax(domain.joint_min_rad(j) - q_rad(j), q_rad(j) - domain.joint_max_rad(j));
    if (beyond_rad > domain.joint_margin_rad && beyond_rad > e.joint_beyond_rad) {
      e.joint = j;
      e.joint_beyond_rad = beyond_rad;
    }
  }
  return e;
}

}  // namespace hivecal
