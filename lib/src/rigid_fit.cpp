#include "hivecal/rigid_fit.hpp"

#include <Eigen/SVD>

namespace hivecal {

void RigidFitAccumulator::add(const Vec3& source_m, const Vec3& target_m, double weight) {
  if (!all_finite(source_m) || !all_finite(target_m) || !math::is_finite(weight)) {
    saw_non_finite_ = true;
    return;
  }
  if (weight < 0.0) {
    saw_bad_weight_ = true;
    return;
  }
  if (weight == 0.0) return;
  if (count_ == 0) {
    source_origin_m_ = source_m;
    target_origin_m_ = target_m;
  }
  const Vec3 s = source_m - source_origin_m_;
  const Vec3 t = target_m - target_origin_m_;
  weight_sum_ += weight;
  source_sum_m_ += weight * s;
  target_sum_m_ += weight * t;
  cross_sum_m2_ += weight * s * t.transpose();
  source_moment_m2_ += weight * s * s.transpose();
  target_moment_m2_ += weight * t * t.transpose();
  ++count_;
}

Mat3 rotation_from_cross_covariance(const Mat3& cross_covariance) {
  const Eigen::JacobiSVD<Mat3> svd(cross_covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Mat3& u = svd.matrixU();
  const Mat3& v = svd.matrixV();
  Mat3 correction = Mat3::Identity();
  if ((v * u.transpose()).determinant() < 0.0) correction(2, 2) = -1.0;
  return v * correction * u.transpose();
}

bool scatter_spans_plane(const Mat3& scatter) {
  const Eigen::JacobiSVD<Mat3> svd(scatter);
  const Vec3& sigma = svd.singularValues();  // sorted, decreasing
  return sigma(0) > 0.0 && sigma(1) > kCollinearityThreshold * sigma(0);
}

Status RigidFitAccumulator::solve(RigidTransform* source_to_target) const {
  if (saw_non_finite_) return Status::non_finite_input;
  if (saw_bad_weight_) return Status::invalid_argument;
  if (count_ < 3) return Status::too_few_samples;
  const Vec3 source_mean = source_sum_m_ / weight_sum_;
  const Vec3 target_mean = target_sum_m_ / weight_sum_;
  const Mat3 cross = cross_sum_m2_ - weight_sum_ * source_mean * target_mean.transpose();
  const Mat3 source_scatter = source_moment_m2_ - weight_sum_ * source_mean * source_mean.transpose();
  const Mat3 target_scatter = target_moment_m2_ - weight_sum_ * target_mean * target_mean.transpose();
  if (!scatter_spans_plane(source_scatter) || !scatter_spans_plane(target_scatter)) {
    return Status::degenerate_geometry;
  }
  const Mat3 rotation = rotation_from_cross_covariance(cross);
  if (!all_finite(rotation)) return Status::degenerate_geometry;
  source_to_target->rotation = rotation;
  source_to_target->translation_m =
      (target_mean + target_origin_m_) - rotation * (source_mean + source_origin_m_);
  return Status::ok;
}

Status fit_rigid_transform(Span<const Vec3> source_m, Span<const Vec3> target_m, Span<const double> weights,
                           RigidTransform* source_to_target) {
  if (source_m.size() != target_m.size()) return Status::invalid_argument;
  if (!weights.empty() && weights.size() != source_m.size()) return Status::invalid_argument;
  RigidFitAccumulator accumulator;
  for (std::size_t i = 0; i < source_m.size(); ++i) {
    accumulator.add(source_m[i], target_m[i], weights.empty() ? 1.0 : weights[i]);
  }
  return accumulator.solve(source_to_target);
}

}  // namespace hivecal
