#include "hivecal/paper6_cost.hpp"

#include <limits>

#include "hivecal/cost.hpp"
#include "hivecal/rigid_fit.hpp"

namespace hivecal {
namespace {

constexpr int kTailCount = static_cast<int>(kPaper6Dimension) - 1;  // a2..d6: the lengths that move centred points
using TailLengths = Eigen::Matrix<double, kTailCount, 1>;
using TailDirections = Eigen::Matrix<double, 3, kTailCount>;

/// A stored term widened to double (exact: float -> double loses nothing).
struct WideTerm {
  Vec3 point_m;
  Vec3 measured_m;  // point + error: the measured point in the reference frame, relative
  TailDirections directions;
};

template <typename Term>
WideTerm widen(const Term& term) {
  WideTerm wide;
  wide.point_m = term.point_m.template cast<double>();
  wide.measured_m = wide.point_m + term.error_m.template cast<double>();
  wide.directions = term.directions.template cast<double>();
  return wide;
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

Status Paper6CostBase::reset(const RobotModel& nominal, const RigidTransform& reference_base_to_tracker) {
  if (!all_finite(to_params(nominal)) || !all_finite(reference_base_to_tracker.rotation) ||
      !all_finite(reference_base_to_tracker.translation_m)) {
    return Status::non_finite_input;
  }
  nominal_ = nominal;
  reference_ = reference_base_to_tracker;
  nominal_lengths_m_ = paper6_lengths(nominal);
  size_ = 0;
  ready_ = false;
  return Status::ok;
}

template <typename Term>
void Paper6CostBase::store(const Vec3& predicted_m, const Vec3& measured_m, const ToolPointJacobian& jacobian,
                           Term* term) const {
  using Scalar = typename Term::Vector::Scalar;
  const Vec3 measured_in_base_m = reference_.rotation.transpose() * (measured_m - reference_.translation_m);
  term->point_m = (predicted_m - point_origin_m_).template cast<Scalar>();
  term->error_m = (measured_in_base_m - predicted_m).template cast<Scalar>();
  for (std::size_t k = 1; k < kPaper6Dimension; ++k) {
    term->directions.col(static_cast<int>(k) - 1) = jacobian.col(kPaper6ParamIndex[k]).template cast<Scalar>();
  }
}

Status Paper6CostBase::add(const JointVector& q_rad, const Vec3& point_m) {
  if (!all_finite(q_rad) || !all_finite(point_m)) return Status::non_finite_input;
  if (size_ == capacity_) return Status::dataset_full;
  ToolPointJacobian jacobian;
  (void)tool_point_jacobian(nominal_, q_rad, &jacobian);
  const Vec3 predicted_m = fk_tool_point(nominal_, q_rad);  // as evaluate_cost computes it
  if (size_ == 0) point_origin_m_ = predicted_m;
  if (terms_ != nullptr) {
    store(predicted_m, point_m, jacobian, &terms_[size_]);
  } else {
    store(predicted_m, point_m, jacobian, &compact_terms_[size_]);
  }
  ++size_;
  ready_ = false;
  return Status::ok;
}

template <typename Term>
Status Paper6CostBase::precompute(const Term* terms) {
  const auto count = static_cast<double>(size_);
  Vec3 point_sum_m = Vec3::Zero();
  Vec3 measured_sum_m = Vec3::Zero();
  TailDirections direction_sum = TailDirections::Zero();
  for (std::size_t i = 0; i < size_; ++i) {
    const WideTerm term = widen(terms[i]);
    point_sum_m += term.point_m;
    measured_sum_m += term.measured_m;
    direction_sum += term.directions;
  }
  point_mean_m_ = point_sum_m / count;
  measured_mean_m_ = measured_sum_m / count;
  const TailDirections tail_direction_mean = direction_sum / count;
  direction_mean_.col(0) = Vec3::UnitZ();  // d1 slides along the base z axis for every pose
  direction_mean_.rightCols<kTailCount>() = tail_direction_mean;

  // Second pass on centred values (the terms stay as they are, so add() may follow).
  Mat3 point_scatter_m2 = Mat3::Zero();
  Mat3 measured_scatter_m2 = Mat3::Zero();
  cross_nominal_m2_.setZero();
  for (Mat3& cross : cross_per_length_m_) cross.setZero();
  for (std::size_t i = 0; i < size_; ++i) {
    const WideTerm term = widen(terms[i]);
    const Vec3 point_m = term.point_m - point_mean_m_;
    const Vec3 measured_m = term.measured_m - measured_mean_m_;
    const TailDirections directions = term.directions - tail_direction_mean;
    point_scatter_m2 += point_m * point_m.transpose();
    measured_scatter_m2 += measured_m * measured_m.transpose();
    cross_nominal_m2_ += point_m * measured_m.transpose();
    for (int k = 0; k < kTailCount; ++k) {
      cross_per_length_m_[k] += directions.col(k) * measured_m.transpose();
    }
  }
  if (!scatter_spans_plane(point_scatter_m2) || !scatter_spans_plane(measured_scatter_m2)) {
    return Status::degenerate_geometry;
  }
  return Status::ok;
}

Status Paper6CostBase::finalize() {
  ready_ = false;
  if (size_ < 3) return Status::too_few_samples;
  const Status status = terms_ != nullptr ? precompute(terms_) : precompute(compact_terms_);
  ready_ = status == Status::ok;
  return status;
}

Status Paper6CostBase::build(const RobotModel& nominal, Span<const Sample> samples) {
  if (samples.empty()) return Status::dataset_empty;
  RigidTransform reference;
  const Status fitted = fit_base_to_tracker(nominal, samples, &reference);
  if (fitted != Status::ok) return fitted;
  const Status reset_status = reset(nominal, reference);
  if (reset_status != Status::ok) return reset_status;
  for (const Sample& sample : samples) {
    const Status added = add(sample.q_rad, sample.point_m);
    if (added != Status::ok) return added;
  }
  return finalize();
}

template <typename Term>
double Paper6CostBase::sum_abs_residuals(const Term* terms, const Mat3& rotation, const Vec3& shift_m,
                                         const double* tail_m) const {
  // The hot loop: read the stored fields in place (cast<double> is free for double terms).
  const Eigen::Map<const TailLengths> tail(tail_m);
  double sum_m = 0.0;
  for (std::size_t i = 0; i < size_; ++i) {
    const Term& term = terms[i];
    const auto point_m = term.point_m.template cast<double>();
    const Vec3 measured_m = point_m + term.error_m.template cast<double>();
    const Vec3 predicted_m = point_m + term.directions.template cast<double>() * tail;
    sum_m += (rotation * predicted_m - measured_m - shift_m).norm();
  }
  return sum_m;
}

double Paper6CostBase::mean_abs_error(const double* lengths_m, RigidTransform* base_to_tracker) const {
  if (!ready_) return std::numeric_limits<double>::quiet_NaN();
  const Paper6Lengths offsets_m = Eigen::Map<const Paper6Lengths>(lengths_m) - nominal_lengths_m_;
  const TailLengths tail_m = offsets_m.tail<kTailCount>();
  // Kabsch in the reference frame on centred points: H(L) = sum p_c(L) m_c^T is affine in L.
  Mat3 cross_m2 = cross_nominal_m2_;
  for (int k = 0; k < kTailCount; ++k) cross_m2 += tail_m(k) * cross_per_length_m_[k];
  const Mat3 rotation = rotation_from_cross_covariance_qcp(cross_m2);
  // r_i = E (p_i(L) - mean p(L)) - (m_i - mean m): the fitted translation cancels; d1 only
  // shifts every p_i(L) alike and drops out.
  const Vec3 shift_m = rotation * (point_mean_m_ + direction_mean_.rightCols<kTailCount>() * tail_m) - measured_mean_m_;
  const double sum_m = terms_ != nullptr ? sum_abs_residuals(terms_, rotation, shift_m, tail_m.data())
                                         : sum_abs_residuals(compact_terms_, rotation, shift_m, tail_m.data());
  if (base_to_tracker != nullptr) {
    // In the reference frame m ~ E p + tau; in the tracker frame R = R_ref E, t = R_ref tau + t_ref.
    const Vec3 tau_m = (point_origin_m_ + measured_mean_m_) -
                       rotation * (point_origin_m_ + point_mean_m_ + direction_mean_ * offsets_m);
    base_to_tracker->rotation = reference_.rotation * rotation;
    base_to_tracker->translation_m = reference_.rotation * tau_m + reference_.translation_m;
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
