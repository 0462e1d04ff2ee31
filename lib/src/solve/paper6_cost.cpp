#include "hivecal/solve/paper6_cost.hpp"

#include <cmath>
#include <limits>

#include "hivecal/solve/cost.hpp"
#include "hivecal/model/rigid_fit.hpp"
#include "core/lanes.hpp"

namespace hivecal {
namespace {

constexpr int kTailCount = static_cast<int>(kPaper6Dimension) - 1;  // a2..d6: the lengths that move centred points
using TailLengths = Eigen::Matrix<double, kTailCount, 1>;
using TailDirections = Eigen::Matrix<double, 3, kTailCount>;

// Positions of the stored values (kPaper6ValuesPerSample): point, error, directions.
constexpr std::size_t kPointValue = 0;
constexpr std::size_t kErrorValue = 3;
constexpr std::size_t kDirectionValue = 6;
static_assert(kDirectionValue + 3 * kTailCount == kPaper6ValuesPerSample, "value layout");
constexpr std::size_t kBlockValues = kPaper6ValuesPerSample * kPaper6BlockSamples;

/// Position of value v of sample i in the block storage.
constexpr std::size_t value_index(std::size_t v, std::size_t i) {
  return i / kPaper6BlockSamples * kBlockValues + v * kPaper6BlockSamples + i % kPaper6BlockSamples;
}

/// A stored sample widened to double (exact: float -> double loses nothing).
struct WideTerm {
  Vec3 point_m;
  Vec3 measured_m;  // point + error: the measured point in the reference frame, relative
  TailDirections directions;
};

/// Sample i of the block storage.
template <typename Scalar>
WideTerm widen(const Scalar* values, std::size_t i) {
  const auto value = [&](std::size_t v) { return static_cast<double>(values[value_index(v, i)]); };
  WideTerm wide;
  for (int r = 0; r < 3; ++r) {
    const auto row = static_cast<std::size_t>(r);
    wide.point_m(r) = value(kPointValue + row);
    wide.measured_m(r) = wide.point_m(r) + value(kErrorValue + row);
    for (int k = 0; k < kTailCount; ++k) wide.directions(r, k) = value(kDirectionValue + 3 * static_cast<std::size_t>(k) + row);
  }
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

template <typename Scalar>
void Paper6CostBase::store(const Vec3& predicted_m, const Vec3& measured_m, const ToolPointJacobian& jacobian,
                           Scalar* values) const {
  const Vec3 measured_in_base_m = reference_.rotation.transpose() * (measured_m - reference_.translation_m);
  const Vec3 point_m = predicted_m - point_origin_m_;
  const Vec3 error_m = measured_in_base_m - predicted_m;
  for (int r = 0; r < 3; ++r) {
    const auto row = static_cast<std::size_t>(r);
    values[value_index(kPointValue + row, size_)] = static_cast<Scalar>(point_m(r));
    values[value_index(kErrorValue + row, size_)] = static_cast<Scalar>(error_m(r));
    for (std::size_t k = 1; k < kPaper6Dimension; ++k) {
      values[value_index(kDirectionValue + 3 * (k - 1) + row, size_)] =
          static_cast<Scalar>(jacobian(r, kPaper6ParamIndex[k]));
    }
  }
}

Status Paper6CostBase::add(const JointVector& q_rad, const Vec3& point_m) {
  if (!all_finite(q_rad) || !all_finite(point_m)) return Status::non_finite_input;
  if (size_ == capacity_) return Status::dataset_full;
  ToolPointJacobian jacobian;
  (void)tool_point_jacobian(nominal_, q_rad, &jacobian);
  const Vec3 predicted_m = fk_tool_point(nominal_, q_rad);  // as evaluate_cost computes it
  if (size_ == 0) point_origin_m_ = predicted_m;
  if (values_ != nullptr) {
    store(predicted_m, point_m, jacobian, values_);
  } else {
    store(predicted_m, point_m, jacobian, compact_values_);
  }
  ++size_;
  ready_ = false;
  return Status::ok;
}

template <typename Scalar>
Status Paper6CostBase::precompute(const Scalar* values) {
  const auto count = static_cast<double>(size_);
  Vec3 point_sum_m = Vec3::Zero();
  Vec3 measured_sum_m = Vec3::Zero();
  TailDirections direction_sum = TailDirections::Zero();
  for (std::size_t i = 0; i < size_; ++i) {
    const WideTerm term = widen(values, i);
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
    const WideTerm term = widen(values, i);
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
  const Status status = values_ != nullptr ? precompute(values_) : precompute(compact_values_);
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

template <typename Scalar>
double Paper6CostBase::sum_abs_residuals(const Scalar* values, const Mat3& rotation, const Vec3& shift_m,
                                         const double* tail_m) const {
  // The hot loop, kLanes samples at a time: two where the target has double SIMD, each value
  // read at a fixed offset from one pointer (left to the auto-vectoriser, the loop kept 21
  // pointers in spilled registers); one without, where pairs would only double the live
  // registers and spill. A block's unused tail is zero-initialised storage, computed and
  // ignored; the norms are summed in sample order. The operation order is Eigen's (pairwise
  // sums in products and norms), which the golden digest pins.
  static_assert(kPaper6BlockSamples % 2 == 0, "whole pairs per block");
  using lanes::Lane;
  using lanes::broadcast;
  using lanes::lane_value;
  constexpr auto kLanes = static_cast<std::size_t>(lanes::kLanes);
  constexpr std::size_t kPoint = kPointValue * kPaper6BlockSamples;
  constexpr std::size_t kError = kErrorValue * kPaper6BlockSamples;
  constexpr std::size_t kDirection = kDirectionValue * kPaper6BlockSamples;
  constexpr std::size_t kRow = kPaper6BlockSamples;         // next row of a value triple
  constexpr std::size_t kColumn = 3 * kPaper6BlockSamples;  // next direction column
  const Lane t0 = broadcast(tail_m[0]), t1 = broadcast(tail_m[1]), t2 = broadcast(tail_m[2]),
             t3 = broadcast(tail_m[3]), t4 = broadcast(tail_m[4]);
  const Lane e00 = broadcast(rotation(0, 0)), e01 = broadcast(rotation(0, 1)), e02 = broadcast(rotation(0, 2));
  const Lane e10 = broadcast(rotation(1, 0)), e11 = broadcast(rotation(1, 1)), e12 = broadcast(rotation(1, 2));
  const Lane e20 = broadcast(rotation(2, 0)), e21 = broadcast(rotation(2, 1)), e22 = broadcast(rotation(2, 2));
  const Lane sx = broadcast(shift_m(0)), sy = broadcast(shift_m(1)), sz = broadcast(shift_m(2));
  double sum_m = 0.0;
  for (std::size_t start = 0; start < size_; start += kPaper6BlockSamples) {
    const Scalar* const block = values + value_index(0, start);
    const std::size_t count = size_ - start < kPaper6BlockSamples ? size_ - start : kPaper6BlockSamples;
    for (std::size_t j = 0; j < count; j += kLanes) {
      const Scalar* const first = block + j;
      // D t of row r: (D0 t0 + D1 t1) + (D2 t2 + (D3 t3 + D4 t4)).
      const auto moved = [first, &t0, &t1, &t2, &t3, &t4](std::size_t r) {
        const Scalar* const d = first + kDirection + r * kRow;
        return (lanes::load(d) * t0 + lanes::load(d + kColumn) * t1) +
               (lanes::load(d + 2 * kColumn) * t2 + (lanes::load(d + 3 * kColumn) * t3 + lanes::load(d + 4 * kColumn) * t4));
      };
      const Lane p0 = lanes::load(first + kPoint), p1 = lanes::load(first + kPoint + kRow),
                 p2 = lanes::load(first + kPoint + 2 * kRow);
      const Lane q0 = p0 + moved(0), q1 = p1 + moved(1), q2 = p2 + moved(2);
      // r = E q - (p + e) - s, E q per row as e_r0 q0 + (e_r1 q1 + e_r2 q2).
      const Lane r0 = ((e00 * q0 + (e01 * q1 + e02 * q2)) - (p0 + lanes::load(first + kError))) - sx;
      const Lane r1 = ((e10 * q0 + (e11 * q1 + e12 * q2)) - (p1 + lanes::load(first + kError + kRow))) - sy;
      const Lane r2 = ((e20 * q0 + (e21 * q1 + e22 * q2)) - (p2 + lanes::load(first + kError + 2 * kRow))) - sz;
      const Lane squared = r0 * r0 + (r1 * r1 + r2 * r2);
      for (std::size_t k = 0; k < kLanes && j + k < count; ++k) sum_m += std::sqrt(lane_value(squared, static_cast<int>(k)));
    }
  }
  return sum_m;
}

double Paper6CostBase::mean_abs_error(const double* lengths_m, RigidTransform* base_to_tracker) const {
  if (!ready_) return std::numeric_limits<double>::quiet_NaN();
  const Paper6Lengths offsets_m = Eigen::Map<const Paper6Lengths>(lengths_m) - nominal_lengths_m_;
  const TailLengths tail_m = offsets_m.tail<kTailCount>();
  // Kabsch in the reference frame on centred points: H(L) = sum p_c(L) m_c^T is affine in L.
  // Entry by entry, each summed in registers in the order k = 0..4 (the same bits as five
  // matrix updates, without storing and reloading the matrix after each).
  Mat3 cross_m2;
  for (int e = 0; e < 9; ++e) {
    double entry_m2 = cross_nominal_m2_.data()[e];
    for (int k = 0; k < kTailCount; ++k) entry_m2 += tail_m(k) * cross_per_length_m_[k].data()[e];
    cross_m2.data()[e] = entry_m2;
  }
  const Mat3 rotation = rotation_from_cross_covariance_qcp(cross_m2);
  // r_i = E (p_i(L) - mean p(L)) - (m_i - mean m): the fitted translation cancels; d1 only
  // shifts every p_i(L) alike and drops out.
  const Vec3 shift_m = rotation * (point_mean_m_ + direction_mean_.rightCols<kTailCount>() * tail_m) - measured_mean_m_;
  const double sum_m = values_ != nullptr ? sum_abs_residuals(values_, rotation, shift_m, tail_m.data())
                                          : sum_abs_residuals(compact_values_, rotation, shift_m, tail_m.data());
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
