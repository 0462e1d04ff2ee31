#include "hivecal/paper6_cost.hpp"

#include <cmath>
#include <limits>

#include "hivecal/rigid_fit.hpp"

namespace hivecal {
namespace {

using TailLengths = Eigen::Matrix<double, static_cast<int>(kPaper6Dimension) - 1, 1>;

/// Offsets from the expansion point of the five lengths that move the centred points (a2..d6);
/// d1 is index 0 and only shifts every point along the base z axis.
TailLengths tail_offsets(const Paper6Lengths& offsets_m) {
  return offsets_m.tail<static_cast<int>(kPaper6Dimension) - 1>();
}

}  // namespace

Paper6Lengths paper6_lengths(const RobotModel& model) {
  const ModelParams params = to_params(model);
  Paper6Lengths lengths_m;
  for (std::size_t k = 0; k < kPaper6Dimension; ++k) lengths_m(static_cast<int>(k)) = params(kPaper6ParamIndex[k]);
  return lengths_m;
}

RobotModel with_paper6_lengths(const RobotModel& model, const double* lengths_m) {
  ModelParams params = to_params(model);
  for (std::size_t k = 0; k < kPaper6Dimension; ++k) params(kPaper6ParamIndex[k]) = lengths_m[k];
  return from_params(params);
}

Status paper6_box(const RobotModel& nominal, double half_width_m, Paper6Box* box) {
  if (!(math::is_finite(half_width_m) && half_width_m > 0.0)) return Status::invalid_argument;
  const Paper6Lengths lengths_m = paper6_lengths(nominal);
  if (!all_finite(lengths_m)) return Status::non_finite_input;
  for (std::size_t k = 0; k < kPaper6Dimension; ++k) {
    box->lower_m[k] = lengths_m(static_cast<int>(k)) - half_width_m;
    box->upper_m[k] = lengths_m(static_cast<int>(k)) + half_width_m;
  }
  return Status::ok;
}

Status Paper6CostBase::reset(const RobotModel& nominal) {
  if (!all_finite(to_params(nominal))) return Status::non_finite_input;
  nominal_ = nominal;
  nominal_lengths_m_ = paper6_lengths(nominal);
  size_ = 0;
  ready_ = false;
  return Status::ok;
}

Status Paper6CostBase::add(const JointVector& q_rad, const Vec3& point_m) {
  if (!all_finite(q_rad) || !all_finite(point_m)) return Status::non_finite_input;
  if (size_ == capacity_) return Status::dataset_full;
  ToolPointJacobian jacobian;
  (void)tool_point_jacobian(nominal_, q_rad, &jacobian);
  // The point from fk_tool_point, as evaluate_cost computes it.
  const Vec3 predicted_m = fk_tool_point(nominal_, q_rad);
  if (size_ == 0) {
    point_origin_m_ = predicted_m;
    measured_origin_m_ = point_m;
  }
  Paper6Term& term = terms_[size_];
  term.point_m = predicted_m - point_origin_m_;
  term.measured_m = point_m - measured_origin_m_;
  for (std::size_t k = 1; k < kPaper6Dimension; ++k) {
    term.directions.col(static_cast<int>(k) - 1) = jacobian.col(kPaper6ParamIndex[k]);
  }
  ++size_;
  ready_ = false;
  return Status::ok;
}

Status Paper6CostBase::finalize() {
  ready_ = false;
  if (size_ < 3) return Status::too_few_samples;
  const auto count = static_cast<double>(size_);
  Vec3 point_sum_m = Vec3::Zero();
  Vec3 measured_sum_m = Vec3::Zero();
  Paper6Directions direction_sum = Paper6Directions::Zero();
  for (std::size_t i = 0; i < size_; ++i) {
    point_sum_m += terms_[i].point_m;
    measured_sum_m += terms_[i].measured_m;
    direction_sum += terms_[i].directions;
  }
  point_mean_m_ = point_sum_m / count;
  measured_mean_m_ = measured_sum_m / count;
  const Paper6Directions tail_direction_mean = direction_sum / count;
  direction_mean_.col(0) = Vec3::UnitZ();  // d1 slides along the base z axis for every pose
  direction_mean_.rightCols<static_cast<int>(kPaper6Dimension) - 1>() = tail_direction_mean;

  // Second pass on centred values (the terms stay as they are, so add() may follow).
  Mat3 point_scatter_m2 = Mat3::Zero();
  Mat3 measured_scatter_m2 = Mat3::Zero();
  cross_nominal_m2_.setZero();
  for (Mat3& cross : cross_per_length_m_) cross.setZero();
  for (std::size_t i = 0; i < size_; ++i) {
    const Vec3 point_m = terms_[i].point_m - point_mean_m_;
    const Vec3 measured_m = terms_[i].measured_m - measured_mean_m_;
    const Paper6Directions directions = terms_[i].directions - tail_direction_mean;
    point_scatter_m2 += point_m * point_m.transpose();
    measured_scatter_m2 += measured_m * measured_m.transpose();
    cross_nominal_m2_ += point_m * measured_m.transpose();
    for (std::size_t k = 0; k + 1 < kPaper6Dimension; ++k) {
      cross_per_length_m_[k] += directions.col(static_cast<int>(k)) * measured_m.transpose();
    }
  }
  if (!scatter_spans_plane(point_scatter_m2) || !scatter_spans_plane(measured_scatter_m2)) {
    return Status::degenerate_geometry;
  }
  ready_ = true;
  return Status::ok;
}

Status Paper6CostBase::build(const RobotModel& nominal, Span<const Sample> samples) {
  if (samples.empty()) return Status::dataset_empty;
  const Status reset_status = reset(nominal);
  if (reset_status != Status::ok) return reset_status;
  for (const Sample& sample : samples) {
    const Status added = add(sample.q_rad, sample.point_m);
    if (added != Status::ok) return added;
  }
  return finalize();
}

double Paper6CostBase::mean_abs_error(const double* lengths_m, RigidTransform* base_to_tracker) const {
  if (!ready_) return std::numeric_limits<double>::quiet_NaN();
  const Paper6Lengths offsets_m = Eigen::Map<const Paper6Lengths>(lengths_m) - nominal_lengths_m_;
  const TailLengths tail_m = tail_offsets(offsets_m);
  // Kabsch on the centred points: H(L) = sum p_c(L) m_c^T is affine in the offsets.
  Mat3 cross_m2 = cross_nominal_m2_;
  for (std::size_t k = 0; k + 1 < kPaper6Dimension; ++k) cross_m2 += tail_m(static_cast<int>(k)) * cross_per_length_m_[k];
  const Mat3 rotation = rotation_from_cross_covariance_qcp(cross_m2);
  // r_i = R (p_i(L) - mean p(L)) - (m_i - mean m): the fitted translation cancels; d1 only
  // shifts every p_i(L) alike and drops out.
  const auto tail_direction_mean = direction_mean_.rightCols<static_cast<int>(kPaper6Dimension) - 1>();
  const Vec3 centroid_shift_m = rotation * (point_mean_m_ + tail_direction_mean * tail_m) - measured_mean_m_;
  double sum_m = 0.0;
  for (std::size_t i = 0; i < size_; ++i) {
    const Paper6Term& term = terms_[i];
    const Vec3 point_m = term.point_m + term.directions * tail_m;
    sum_m += (rotation * point_m - term.measured_m - centroid_shift_m).norm();
  }
  if (base_to_tracker != nullptr) {
    base_to_tracker->rotation = rotation;
    base_to_tracker->translation_m = (measured_origin_m_ + measured_mean_m_) -
                                     rotation * (point_origin_m_ + point_mean_m_ + direction_mean_ * offsets_m);
  }
  return sum_m / static_cast<double>(size_);
}

Status Paper6CostBase::evaluate(const Paper6Lengths& lengths_m, double* mae_m, RigidTransform* base_to_tracker) const {
  if (!ready_) return Status::invalid_argument;
  if (!all_finite(lengths_m)) return Status::non_finite_input;
  const double value_m = mean_abs_error(lengths_m.data(), base_to_tracker);
  if (!math::is_finite(value_m)) return Status::non_finite_input;
  *mae_m = value_m;
  return Status::ok;
}

}  // namespace hivecal
