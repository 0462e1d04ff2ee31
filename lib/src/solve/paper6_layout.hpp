// The paper-6 cost's storage layout (Paper6CostBase, solve/paper6_cost.hpp), shared by its
// setup (paper6_cost_setup.cpp: the nominal model, the samples, the precomputed sums; run once
// per cost, compiled for size on bare metal) and its evaluation (paper6_cost.cpp: the hot
// residual pass).
#pragma once

#include <cstddef>
#include <type_traits>

#include "hivecal/solve/paper6_cost.hpp"

namespace hivecal::paper6_layout {

inline constexpr int kMaxStored = static_cast<int>(kMaxLinkLengths);  // columns stored per sample, at most
using StoredDirections = Eigen::Matrix<double, 3, kMaxStored>;

// Positions of the stored values: point, error, directions (values_per_sample_ in all).
inline constexpr std::size_t kPointValue = 0;
inline constexpr std::size_t kErrorValue = 3;
inline constexpr std::size_t kDirectionValue = 6;
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
inline WideTerm widen(const Scalar* values, std::size_t i, std::size_t per_sample, int stored) {
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

/// The storage of scalar Scalar: the exact (double) or the compact (float) values.
template <typename Scalar>
inline Scalar* storage_of(double* values, float* compact_values) {
  if constexpr (std::is_same_v<Scalar, double>) {
    (void)compact_values;
    return values;
  } else {
    (void)values;
    return compact_values;
  }
}

}  // namespace hivecal::paper6_layout
