#include "hivecal/solve/paper6_cost.hpp"

#include <cmath>
#include <limits>

#include "hivecal/model/rigid_fit.hpp"
#include "core/lanes.hpp"
#include "solve/paper6_layout.hpp"

namespace hivecal {
namespace {

/// sum_k columns.col(begin + k) * t[begin + k] over `count` columns, summed in halves
/// recursively: the order of Eigen's unrolled fixed-size products, so that the paper's six
/// lengths keep the bits they had as fixed-size Eigen expressions (golden digests).
Vec3 combine(const paper6_layout::StoredDirections& columns, const double* t, int begin, int count) {
  if (count == 0) return Vec3::Zero();
  if (count == 1) return columns.col(begin) * t[begin];
  const int half = count / 2;
  return combine(columns, t, begin, half) + combine(columns, t, begin + half, count - half);
}

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
  constexpr std::size_t kPoint = paper6_layout::kPointValue * kPaper6BlockSamples;
  constexpr std::size_t kError = paper6_layout::kErrorValue * kPaper6BlockSamples;
  constexpr std::size_t kDirection = paper6_layout::kDirectionValue * kPaper6BlockSamples;
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
  paper6_layout::StoredDirections stored_mean = paper6_layout::StoredDirections::Zero();
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
  return cost.mean_abs_error(paper6_layout::storage_of<Scalar>(cost.values_, cost.compact_values_), lengths_m,
                             base_to_tracker);
}

// The instantiations the constructors name (an image links those its costs use).
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
