#include "hivecal/model/rigid_fit.hpp"

#include "hivecal/model/kinematics.hpp"

#include <Eigen/SVD>
#include <cmath>

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
  source_to_target->translation_m = (target_mean + target_origin_m_) - rotation * (source_mean + source_origin_m_);
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

namespace hivecal {
namespace {

using Mat4 = Eigen::Matrix<double, 4, 4>;

/// Horn's symmetric key matrix of S = sum s t^T: q^T N q = sum t . (R(q) s) for unit q.
Mat4 horn_key_matrix(const Mat3& s) {
  const double sxx = s(0, 0), sxy = s(0, 1), sxz = s(0, 2);
  const double syx = s(1, 0), syy = s(1, 1), syz = s(1, 2);
  const double szx = s(2, 0), szy = s(2, 1), szz = s(2, 2);
  Mat4 n;
  n << sxx + syy + szz, syz - szy, szx - sxz, sxy - syx, syz - szy, sxx - syy - szz, sxy + syx, szx + sxz, szx - sxz,
      sxy + syx, -sxx + syy - szz, syz + szy, sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz;
  return n;
}

/// Rows (or columns) left when index `skip` of four is deleted.
constexpr int kKept[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};

/// Determinant of a's 3x3 minor without row `Row` and column `Col`. Indices known at compile
/// time, so that it inlines to its 14 flops (it runs 7 times per rotation fit).
template <int Row, int Col>
double minor_at(const Mat4& a) {
  constexpr int r0 = kKept[Row][0], r1 = kKept[Row][1], r2 = kKept[Row][2];
  constexpr int c0 = kKept[Col][0], c1 = kKept[Col][1], c2 = kKept[Col][2];
  return a(r0, c0) * (a(r1, c1) * a(r2, c2) - a(r1, c2) * a(r2, c1)) -
         a(r0, c1) * (a(r1, c0) * a(r2, c2) - a(r1, c2) * a(r2, c0)) +
         a(r0, c2) * (a(r1, c0) * a(r2, c1) - a(r1, c1) * a(r2, c0));
}

/// The four minors of row `Row` of a, the diagonal one already known.
template <int Row>
void row_minors(const Mat4& a, double diagonal_minor, double* minors) {
  minors[0] = Row == 0 ? diagonal_minor : minor_at<Row, 0>(a);
  minors[1] = Row == 1 ? diagonal_minor : minor_at<Row, 1>(a);
  minors[2] = Row == 2 ? diagonal_minor : minor_at<Row, 2>(a);
  minors[3] = Row == 3 ? diagonal_minor : minor_at<Row, 3>(a);
}

/// Largest root of x^4 + c2 x^2 + c1 x + c0 (all roots real: N is symmetric) by Newton's
/// method from an upper bound: monotone from above, so it stops when x no longer decreases.
double largest_quartic_root(double c2, double c1, double c0, double upper_bound) {
  constexpr int kMaxSteps = 64;
  double x = upper_bound;
  for (int step = 0; step < kMaxSteps; ++step) {
    const double x2 = x * x;
    const double value = (x2 + c2) * x2 + c1 * x + c0;
    const double slope = (4.0 * x2 + 2.0 * c2) * x + c1;
    const double next = x - value / slope;
    if (!(next < x)) break;
    x = next;
  }
  return x;
}

Mat3 rotation_of_quaternion(const Eigen::Matrix<double, 4, 1>& q) {
  const double w = q(0), x = q(1), y = q(2), z = q(3);
  Mat3 r;
  r << w * w + x * x - y * y - z * z, 2.0 * (x * y - w * z), 2.0 * (x * z + w * y), 2.0 * (x * y + w * z),
      w * w - x * x + y * y - z * z, 2.0 * (y * z - w * x), 2.0 * (x * z - w * y), 2.0 * (y * z + w * x),
      w * w - x * x - y * y + z * z;
  return r;
}

}  // namespace

Mat3 rotation_from_cross_covariance_qcp(const Mat3& cross_covariance) {
  // Below this, the top eigenvalue is too close to the next one for the cofactor eigenvector.
  constexpr double kMinRelativeCofactor = 1e-3;
  const Mat4 key = horn_key_matrix(cross_covariance);
  const double frobenius_squared = cross_covariance.squaredNorm();
  // Characteristic polynomial of N (trace 0): x^4 - 2|S|^2 x^2 - 8 det(S) x + det(N).
  // sqrt(3)|S| >= s1 + s2 + s3 >= the largest eigenvalue.
  const double lambda = largest_quartic_root(-2.0 * frobenius_squared, -8.0 * cross_covariance.determinant(),
                                             key.determinant(), std::sqrt(3.0 * frobenius_squared));
  const Mat4 shifted = key - lambda * Mat4::Identity();
  // The adjugate of N - lambda I is q q^T times a scalar: its best-scaled column is the eigenvector.
  const double diagonal_minors[4] = {minor_at<0, 0>(shifted), minor_at<1, 1>(shifted), minor_at<2, 2>(shifted),
                                     minor_at<3, 3>(shifted)};
  int column = 0;
  double largest = 0.0;
  for (int j = 0; j < 4; ++j) {
    const double diagonal = std::fabs(diagonal_minors[j]);
    if (diagonal > largest) {
      largest = diagonal;
      column = j;
    }
  }
  if (!(largest > kMinRelativeCofactor * lambda * lambda * lambda)) {
    return rotation_from_cross_covariance(cross_covariance);
  }
  double minors[4];
  switch (column) {
    case 0: row_minors<0>(shifted, diagonal_minors[0], minors); break;
    case 1: row_minors<1>(shifted, diagonal_minors[1], minors); break;
    case 2: row_minors<2>(shifted, diagonal_minors[2], minors); break;
    default: row_minors<3>(shifted, diagonal_minors[3], minors); break;
  }
  Eigen::Matrix<double, 4, 1> q;
  for (int i = 0; i < 4; ++i) q(i) = (i + column) % 2 == 0 ? minors[i] : -minors[i];
  return rotation_of_quaternion(q / q.norm());
}

Status fit_base_to_tracker(const RobotModel& model, Span<const Sample> samples, RigidTransform* base_to_tracker) {
  RigidFitAccumulator accumulator;
  for (const Sample& sample : samples) accumulator.add(fk_sample_point(model, sample), sample.point_m);
  return accumulator.solve(base_to_tracker);
}

Status fit_base_and_target_tools(Span<const Sample> samples, RobotModel* model, RigidTransform* base_to_tracker) {
  constexpr int kRounds = 3;  // from tools at the flange, 1 mm after two rounds on test data
  Status status = fit_base_to_tracker(*model, samples, base_to_tracker);
  if (status != Status::ok || target_count(samples) == 1) return status;
  for (int round = 0; round < kRounds && status == Status::ok; ++round) {
    fit_other_target_tools(*base_to_tracker, samples, model);
    status = fit_base_to_tracker(*model, samples, base_to_tracker);
  }
  fit_other_target_tools(*base_to_tracker, samples, model);
  return status;
}

void fit_other_target_tools(const RigidTransform& base_to_tracker, Span<const Sample> samples, RobotModel* model) {
  Vec3 sum_m[kMaxTargets];
  int count[kMaxTargets] = {};
  for (Vec3& sum : sum_m) sum.setZero();
  for (const Sample& sample : samples) {
    if (sample.target == 0) continue;
    const RigidTransform flange = fk_flange(*model, sample.q_rad);
    const Vec3 in_base_m = base_to_tracker.inverse().apply(sample.point_m);
    sum_m[sample.target] += flange.rotation.transpose() * (in_base_m - flange.translation_m);
    ++count[sample.target];
  }
  for (int target = 1; target < kMaxTargets; ++target) {
    if (count[target] > 0) target_tool(model, target) = sum_m[target] / static_cast<double>(count[target]);
  }
}

}  // namespace hivecal
