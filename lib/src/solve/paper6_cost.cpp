#include "hivecal/solve/paper6_cost.hpp"

#include <cmath>
#include <limits>
#include <type_traits>

#include "hivecal/solve/cost.hpp"
#include "hivecal/model/rigid_fit.hpp"
#include "core/lanes.hpp"

namespace hivecal {
namespace {

constexpr int kMaxStored = static_cast<int>(kMaxLinkLengths);  // columns stored per sample, at most
using StoredDirections = Eigen::Matrix<double, 3, kMaxStored>;

// Positions of the stored values: point, error, directions (values_per_sample_ in all).
constexpr std::size_t kPointValue = 0;
constexpr std::size_t kErrorValue = 3;
constexpr std::size_t kDirectionValue = 6;
static_assert(kDirectionValue + 3 * (kPaper6Dimension - 1) == kPaper6ValuesPerSample, "value layout");

/// Position of value v of sample i in a block storage of `per_sample` values per sample.
constexpr std::size_t value_index(std::size_t v, std::size_t i, std::size_t per_sample) {
  return i / kPaper6BlockSamples * (per_sample * kPaper6BlockSamples) + v * kPaper6BlockSamples +
         i % kPaper6BlockSamples;
}

/// A stored sample widened to double (exact: float -> double loses nothing).
struct WideTerm {
  Vec3 point_m;
  Vec3 measured_m;              // point + error: the measured point in the reference frame, relative
  StoredDirections directions;  // the first `stored` columns
};

/// Sample i of the block storage.
template <typename Scalar>
WideTerm widen(const Scalar* values, std::size_t i, std::size_t per_sample, int stored) {
  const auto value = [&](std::size_t v) { return static_cast<double>(values[value_index(v, i, per_sample)]); };
  WideTerm wide;
  wide.directions.setZero();
  for (int r = 0; r < 3; ++r) {
    const auto row = static_cast<std::size_t>(r);
    wide.point_m(r) = value(kPointValue + row);
    wide.measured_m(r) = wide.point_m(r) + value(kErrorValue + row);
    for (int k = 0; k < stored; ++k)
      wide.directions(r, k) = value(kDirectionValue + 3 * static_cast<std::size_t>(k) + row);
  }
  return wide;
}

/// sum_k columns.col(begin + k) * t[begin + k] over `count` columns, summed in halves
/// recursively: the order of Eigen's unrolled fixed-size products, so that the paper's six
/// lengths keep the bits they had as fixed-size Eigen expressions (golden digests).
Vec3 combine(const StoredDirections& columns, const double* t, int begin, int count) {
  if (count == 0) return Vec3::Zero();
  if (count == 1) return columns.col(begin) * t[begin];
  const int half = count / 2;
  return combine(columns, t, begin, half) + combine(columns, t, begin + half, count - half);
}

}  // namespace

LinkLengthSet link_length_set(const RobotModel& nominal) {
  const ModelParams params = to_params(nominal);
  LinkLengthSet set;
  for (int j = 0; j < nominal.joint_count; ++j) {
    for (DhField field : {DhField::d, DhField::a}) {
      const int index = model_param_index(j, field);
      if (params(index) != 0.0) set.param_index[set.count++] = index;
    }
  }
  return set;
}

LinkLengths link_lengths(const RobotModel& model, const LinkLengthSet& set) {
  const ModelParams params = to_params(model);
  LinkLengths lengths_m;
  lengths_m.count = set.count;
  for (std::size_t k = 0; k < set.count; ++k) lengths_m.data()[k] = params(set.param_index[k]);
  return lengths_m;
}

LinkLengths link_lengths(const RobotModel& model) {
  return link_lengths(model, link_length_set(model));
}

RobotModel with_link_lengths(const RobotModel& model, const LinkLengthSet& set, const double* lengths_m) {
  ModelParams params = to_params(model);
  for (std::size_t k = 0; k < set.count; ++k) params(set.param_index[k]) = lengths_m[k];
  RobotModel out;  // rigid: the compliance is not the lengths' (with_link_lengths' contract)
  out.joint_count = model.joint_count;
  out.prismatic_joints = model.prismatic_joints;
  set_model_params(params, &out);
  for (int k = 0; k < kMaxTargets - 1; ++k) out.other_tools_m[k] = model.other_tools_m[k];  // not among the parameters
  return out;
}

Status link_length_box(const RobotModel& nominal, double half_width_m, LinkLengthBox* box) {
  if (!(math::is_finite(half_width_m) && half_width_m > 0.0)) return Status::invalid_argument;
  const LinkLengthSet set = link_length_set(nominal);
  if (set.count == 0) return Status::invalid_argument;
  const LinkLengths lengths_m = link_lengths(nominal, set);
  if (!all_finite(lengths_m.values_m)) return Status::non_finite_input;
  box->count = set.count;
  for (std::size_t k = 0; k < set.count; ++k) {
    box->lower_m[k] = lengths_m.data()[k] - half_width_m;
    box->upper_m[k] = lengths_m.data()[k] + half_width_m;
  }
  return Status::ok;
}

Paper6CostView::Paper6CostView(Span<double> values, std::size_t max_lengths)
    : Paper6CostBase(values.data(), paper6_capacity_of(values.size(), max_lengths), max_lengths) {
  for (double& value : values) value = 0.0;
}

Status Paper6CostBase::reset(const RobotModel& nominal, const RigidTransform& reference_base_to_tracker) {
  if (!all_finite(to_params(nominal)) || !all_finite(reference_base_to_tracker.rotation) ||
      !all_finite(reference_base_to_tracker.translation_m)) {
    return Status::non_finite_input;
  }
  const LinkLengthSet set = link_length_set(nominal);
  const std::size_t stored = set.has_d1() ? set.count - 1 : set.count;
  const std::size_t per_sample = kDirectionValue + 3 * stored;
  if (set.count == 0 || per_sample > max_values_per_sample_) return Status::dimension_out_of_range;
  nominal_ = nominal;
  reference_ = reference_base_to_tracker;
  set_ = set;
  stored_count_ = stored;
  values_per_sample_ = per_sample;
  const LinkLengths lengths_m = link_lengths(nominal, set);
  for (std::size_t k = 0; k < set.count; ++k) nominal_lengths_m_[k] = lengths_m.data()[k];
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
  const std::size_t first = set_.count - stored_count_;  // d1 (not stored) comes first
  for (int r = 0; r < 3; ++r) {
    const auto row = static_cast<std::size_t>(r);
    values[value_index(kPointValue + row, size_, values_per_sample_)] = static_cast<Scalar>(point_m(r));
    values[value_index(kErrorValue + row, size_, values_per_sample_)] = static_cast<Scalar>(error_m(r));
    for (std::size_t k = 0; k < stored_count_; ++k) {
      values[value_index(kDirectionValue + 3 * k + row, size_, values_per_sample_)] =
          static_cast<Scalar>(jacobian(r, set_.param_index[first + k]));
    }
  }
}

Status Paper6CostBase::add(const JointVector& q_rad, const Vec3& point_m, int target) {
  if (!all_finite(q_rad) || !all_finite(point_m)) return Status::non_finite_input;
  if (target < 0 || target >= kMaxTargets) return Status::invalid_argument;
  if (size_ == capacity_) return Status::dataset_full;
  // The point is affine in the link lengths for any tool point: the target's own one.
  RobotModel target_model = nominal_;
  target_model.tool_m = target_tool(nominal_, target);
  ToolPointJacobian jacobian;
  (void)tool_point_jacobian(target_model, q_rad, &jacobian);
  const Vec3 predicted_m = fk_tool_point(target_model, q_rad);  // as evaluate_cost computes it
  if (size_ == 0) point_origin_m_ = predicted_m;
  scalar_.store(*this, predicted_m, point_m, jacobian);
  ++size_;
  ready_ = false;
  return Status::ok;
}

template <typename Scalar>
Status Paper6CostBase::precompute(const Scalar* values) {
  const auto count = static_cast<double>(size_);
  Vec3 point_sum_m = Vec3::Zero();
  Vec3 measured_sum_m = Vec3::Zero();
  const auto stored = static_cast<int>(stored_count_);
  StoredDirections direction_sum = StoredDirections::Zero();
  for (std::size_t i = 0; i < size_; ++i) {
    const WideTerm term = widen(values, i, values_per_sample_, stored);
    point_sum_m += term.point_m;
    measured_sum_m += term.measured_m;
    direction_sum += term.directions;
  }
  point_mean_m_ = point_sum_m / count;
  measured_mean_m_ = measured_sum_m / count;
  const StoredDirections stored_direction_mean = direction_sum / count;
  // All K columns: d1 (when a link length) slides along the base z axis for every pose.
  const int first = set_.has_d1() ? 1 : 0;
  direction_mean_.setZero();
  if (first == 1) direction_mean_.col(0) = Vec3::UnitZ();
  for (int k = 0; k < stored; ++k) direction_mean_.col(first + k) = stored_direction_mean.col(k);

  // Second pass on centred values (the terms stay as they are, so add() may follow).
  Mat3 point_scatter_m2 = Mat3::Zero();
  Mat3 measured_scatter_m2 = Mat3::Zero();
  cross_nominal_m2_.setZero();
  for (Mat3& cross : cross_per_length_m_) cross.setZero();
  for (std::size_t i = 0; i < size_; ++i) {
    const WideTerm term = widen(values, i, values_per_sample_, stored);
    const Vec3 point_m = term.point_m - point_mean_m_;
    const Vec3 measured_m = term.measured_m - measured_mean_m_;
    point_scatter_m2 += point_m * point_m.transpose();
    measured_scatter_m2 += measured_m * measured_m.transpose();
    cross_nominal_m2_ += point_m * measured_m.transpose();
    for (int k = 0; k < stored; ++k) {
      const Vec3 direction = term.directions.col(k) - stored_direction_mean.col(k);
      cross_per_length_m_[k] += direction * measured_m.transpose();
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
  const Status status = scalar_.precompute(*this);
  ready_ = status == Status::ok;
  return status;
}

Status Paper6CostBase::build(const RobotModel& nominal, Span<const Sample> samples) {
  return build(nominal, samples, Span<const std::uint32_t>());
}

Status Paper6CostBase::build(const RobotModel& nominal, Span<const Sample> samples,
                             Span<const std::uint32_t> selection) {
  if (samples.empty()) return Status::dataset_empty;
  for (const std::uint32_t position : selection) {
    if (position >= samples.size()) return Status::invalid_argument;
  }
  RigidTransform reference;
  const Status fitted = fit_base_to_tracker(nominal, samples, &reference);
  if (fitted != Status::ok) return fitted;
  const Status reset_status = reset(nominal, reference);
  if (reset_status != Status::ok) return reset_status;
  const std::size_t count = selection.empty() ? samples.size() : selection.size();
  for (std::size_t k = 0; k < count; ++k) {
    const Sample& sample = samples[selection.empty() ? k : selection[k]];
    const Status added = add(sample.q_rad, sample.point_m, sample.target);
    if (added != Status::ok) return added;
  }
  return finalize();
}

namespace {

/// D t of one row for the generic column count: columns [begin, begin + count) summed in
/// halves recursively (the order of the five-column expression below).
template <typename Scalar>
lanes::Lane moved_row(const Scalar* d, const lanes::Lane* t, std::size_t column_stride, int begin, int count) {
  if (count == 1) return lanes::load(d + static_cast<std::size_t>(begin) * column_stride) * t[begin];
  const int half = count / 2;
  return moved_row(d, t, column_stride, begin, half) + moved_row(d, t, column_stride, begin + half, count - half);
}

/// The residual pass over `size` samples stored `per_sample` values each with `stored`
/// direction columns; kFive: the paper's five stored columns unrolled (UR arms), else generic.
template <bool kFive, typename Scalar>
double residual_pass(const Scalar* values, std::size_t size, std::size_t per_sample, int stored, const Mat3& rotation,
                     const Vec3& shift_m, const double* tail_m) {
  // The hot loop, kLanes samples at a time: two where the target has double SIMD, each value
  // read at a fixed offset from one pointer (left to the auto-vectoriser, the loop kept 21
  // pointers in spilled registers); one without, where pairs would only double the live
  // registers and spill. A block's unused tail is zero-initialised storage, computed and
  // ignored; the norms are summed in sample order. The operation order is Eigen's (pairwise
  // sums in products and norms), which the golden digest pins; the generic column sum keeps it.
  static_assert(kPaper6BlockSamples % 2 == 0, "whole pairs per block");
  using lanes::broadcast;
  using lanes::Lane;
  using lanes::lane_value;
  constexpr auto kLanes = static_cast<std::size_t>(lanes::kLanes);
  constexpr std::size_t kPoint = kPointValue * kPaper6BlockSamples;
  constexpr std::size_t kError = kErrorValue * kPaper6BlockSamples;
  constexpr std::size_t kDirection = kDirectionValue * kPaper6BlockSamples;
  constexpr std::size_t kRow = kPaper6BlockSamples;         // next row of a value triple
  constexpr std::size_t kColumn = 3 * kPaper6BlockSamples;  // next direction column
  Lane t[kMaxLinkLengths] = {};
  for (int k = 0; k < stored; ++k) t[k] = broadcast(tail_m[k]);
  const Lane t0 = t[0], t1 = t[1], t2 = t[2], t3 = t[3], t4 = t[4];  // the paper's five (unused otherwise)
  const Lane e00 = broadcast(rotation(0, 0)), e01 = broadcast(rotation(0, 1)), e02 = broadcast(rotation(0, 2));
  const Lane e10 = broadcast(rotation(1, 0)), e11 = broadcast(rotation(1, 1)), e12 = broadcast(rotation(1, 2));
  const Lane e20 = broadcast(rotation(2, 0)), e21 = broadcast(rotation(2, 1)), e22 = broadcast(rotation(2, 2));
  const Lane sx = broadcast(shift_m(0)), sy = broadcast(shift_m(1)), sz = broadcast(shift_m(2));
  const Lane zero = broadcast(0.0);
  const std::size_t block_values = per_sample * kPaper6BlockSamples;
  double sum_m = 0.0;
  for (std::size_t start = 0; start < size; start += kPaper6BlockSamples) {
    const Scalar* const block = values + start / kPaper6BlockSamples * block_values;
    const std::size_t count = size - start < kPaper6BlockSamples ? size - start : kPaper6BlockSamples;
    for (std::size_t j = 0; j < count; j += kLanes) {
      const Scalar* const first = block + j;
      // D t of row r; for five columns (D0 t0 + D1 t1) + (D2 t2 + (D3 t3 + D4 t4)).
      const auto moved = [&](std::size_t r) {
        const Scalar* const d = first + kDirection + r * kRow;
        if constexpr (kFive) {
          return (lanes::load(d) * t0 + lanes::load(d + kColumn) * t1) +
                 (lanes::load(d + 2 * kColumn) * t2 +
                  (lanes::load(d + 3 * kColumn) * t3 + lanes::load(d + 4 * kColumn) * t4));
        } else {
          return stored == 0 ? zero : moved_row(d, t, kColumn, 0, stored);
        }
      };
      const Lane p0 = lanes::load(first + kPoint), p1 = lanes::load(first + kPoint + kRow),
                 p2 = lanes::load(first + kPoint + 2 * kRow);
      const Lane q0 = p0 + moved(0), q1 = p1 + moved(1), q2 = p2 + moved(2);
      // r = E q - (p + e) - s, E q per row as e_r0 q0 + (e_r1 q1 + e_r2 q2).
      const Lane r0 = ((e00 * q0 + (e01 * q1 + e02 * q2)) - (p0 + lanes::load(first + kError))) - sx;
      const Lane r1 = ((e10 * q0 + (e11 * q1 + e12 * q2)) - (p1 + lanes::load(first + kError + kRow))) - sy;
      const Lane r2 = ((e20 * q0 + (e21 * q1 + e22 * q2)) - (p2 + lanes::load(first + kError + 2 * kRow))) - sz;
      const Lane squared = r0 * r0 + (r1 * r1 + r2 * r2);
      for (std::size_t k = 0; k < kLanes && j + k < count; ++k)
        sum_m += std::sqrt(lane_value(squared, static_cast<int>(k)));
    }
  }
  return sum_m;
}

}  // namespace

template <typename Scalar>
double Paper6CostBase::sum_abs_residuals(const Scalar* values, const Mat3& rotation, const Vec3& shift_m,
                                         const double* tail_m) const {
  const auto stored = static_cast<int>(stored_count_);
  return stored == 5 ? residual_pass<true>(values, size_, values_per_sample_, stored, rotation, shift_m, tail_m)
                     : residual_pass<false>(values, size_, values_per_sample_, stored, rotation, shift_m, tail_m);
}

namespace {

/// The storage of scalar Scalar: the exact (double) or the compact (float) values.
template <typename Scalar>
Scalar* storage_of(double* values, float* compact_values) {
  if constexpr (std::is_same_v<Scalar, double>) {
    (void)compact_values;
    return values;
  } else {
    (void)values;
    return compact_values;
  }
}

}  // namespace

template <typename Scalar>
void Paper6CostBase::store_on(Paper6CostBase& cost, const Vec3& predicted_m, const Vec3& measured_m,
                              const ToolPointJacobian& jacobian) {
  cost.store(predicted_m, measured_m, jacobian, storage_of<Scalar>(cost.values_, cost.compact_values_));
}

template <typename Scalar>
Status Paper6CostBase::precompute_on(Paper6CostBase& cost) {
  return cost.precompute(storage_of<Scalar>(cost.values_, cost.compact_values_));
}

template <typename Scalar>
double Paper6CostBase::mean_abs_error(const Scalar* values, const double* lengths_m,
                                      RigidTransform* base_to_tracker) const {
  if (!ready_) return std::numeric_limits<double>::quiet_NaN();
  const auto count = static_cast<int>(set_.count);
  const auto stored = static_cast<int>(stored_count_);
  const int first = count - stored;  // 1 when d1 is a link length (its column is not stored)
  double offsets_m[kMaxLinkLengths] = {};
  for (int k = 0; k < count; ++k) offsets_m[k] = lengths_m[k] - nominal_lengths_m_[k];
  const double* const tail_m = offsets_m + first;
  // Kabsch in the reference frame on centred points: H(L) = sum p_c(L) m_c^T is affine in L.
  // Entry by entry, each summed in registers in the order k = 0..K-1 (the same bits as K
  // matrix updates, without storing and reloading the matrix after each).
  Mat3 cross_m2;
  for (int e = 0; e < 9; ++e) {
    double entry_m2 = cross_nominal_m2_.data()[e];
    for (int k = 0; k < stored; ++k) entry_m2 += tail_m[k] * cross_per_length_m_[k].data()[e];
    cross_m2.data()[e] = entry_m2;
  }
  const Mat3 rotation = rotation_from_cross_covariance_qcp(cross_m2);
  // r_i = E (p_i(L) - mean p(L)) - (m_i - mean m): the fitted translation cancels; d1 only
  // shifts every p_i(L) alike and drops out.
  StoredDirections stored_mean = StoredDirections::Zero();
  for (int k = 0; k < stored; ++k) stored_mean.col(k) = direction_mean_.col(first + k);
  const Vec3 shift_m = rotation * (point_mean_m_ + combine(stored_mean, tail_m, 0, stored)) - measured_mean_m_;
  const double sum_m = sum_abs_residuals(values, rotation, shift_m, tail_m);
  if (base_to_tracker != nullptr) {
    // In the reference frame m ~ E p + tau; in the tracker frame R = R_ref E, t = R_ref tau + t_ref.
    const Vec3 tau_m = (point_origin_m_ + measured_mean_m_) -
                       rotation * (point_origin_m_ + point_mean_m_ + combine(direction_mean_, offsets_m, 0, count));
    base_to_tracker->rotation = reference_.rotation * rotation;
    base_to_tracker->translation_m = reference_.rotation * tau_m + reference_.translation_m;
  }
  return sum_m / static_cast<double>(size_);
}

template <typename Scalar>
double Paper6CostBase::mean_abs_error_on(const Paper6CostBase& cost, const double* lengths_m,
                                         RigidTransform* base_to_tracker) {
  return cost.mean_abs_error(storage_of<Scalar>(cost.values_, cost.compact_values_), lengths_m, base_to_tracker);
}

// The instantiations the constructors name (an image links those its costs use).
template void Paper6CostBase::store_on<double>(Paper6CostBase&, const Vec3&, const Vec3&, const ToolPointJacobian&);
template void Paper6CostBase::store_on<float>(Paper6CostBase&, const Vec3&, const Vec3&, const ToolPointJacobian&);
template Status Paper6CostBase::precompute_on<double>(Paper6CostBase&);
template Status Paper6CostBase::precompute_on<float>(Paper6CostBase&);
template double Paper6CostBase::mean_abs_error_on<double>(const Paper6CostBase&, const double*, RigidTransform*);
template double Paper6CostBase::mean_abs_error_on<float>(const Paper6CostBase&, const double*, RigidTransform*);

Status Paper6CostBase::evaluate(const LinkLengths& lengths_m, double* mae_m, RigidTransform* base_to_tracker) const {
  if (!ready_ || lengths_m.count != set_.count) return Status::invalid_argument;
  for (std::size_t k = 0; k < set_.count; ++k) {
    if (!math::is_finite(lengths_m.data()[k])) return Status::non_finite_input;
  }
  const double value_m = scalar_.mean_abs_error(*this, lengths_m.data(), base_to_tracker);
  if (!math::is_finite(value_m)) return Status::non_finite_input;
  *mae_m = value_m;
  return Status::ok;
}

}  // namespace hivecal
