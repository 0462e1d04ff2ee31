// Standard benchmark functions as hivecal::Objective, for the population solver tests.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/core/math.hpp"
#include "hivecal/solve/objective.hpp"

namespace hivecal::test {

/// sum x_d^2; minimum 0 at the origin.
inline double sphere_value(const double* x, std::size_t dimension) {
  double sum = 0.0;
  for (std::size_t d = 0; d < dimension; ++d) sum += x[d] * x[d];
  return sum;
}

/// sum 100 (x_{d+1} - x_d^2)^2 + (1 - x_d)^2; minimum 0 at (1, ..., 1).
inline double rosenbrock_value(const double* x, std::size_t dimension) {
  double sum = 0.0;
  for (std::size_t d = 0; d + 1 < dimension; ++d) {
    const double valley = x[d + 1] - x[d] * x[d];
    sum += 100.0 * valley * valley + (1.0 - x[d]) * (1.0 - x[d]);
  }
  return sum;
}

/// 10 D + sum x_d^2 - 10 cos(2 pi x_d); minimum 0 at the origin, a local minimum near every integer point.
inline double rastrigin_value(const double* x, std::size_t dimension) {
  double sum = 10.0 * static_cast<double>(dimension);
  for (std::size_t d = 0; d < dimension; ++d) sum += x[d] * x[d] - 10.0 * math::cos(2.0 * math::kPi * x[d]);
  return sum;
}

/// The same value everywhere: no move ever improves (exercises trial counters and scouts).
inline double flat_value(const double*, std::size_t) {
  return 1.0;
}

/// NaN everywhere except near the origin, where it is the sphere.
inline double mostly_nan_value(const double* x, std::size_t dimension) {
  const double sum = sphere_value(x, dimension);
  return sum < 1.0 ? sum : 0.0 / (sum - sum);
}

/// The function `Value` of x[0..D) as an Objective that counts its evaluations, so tests can
/// check the solvers' own count.
template <double (*Value)(const double*, std::size_t)>
class CountingObjective final : public Objective {
 public:
  explicit CountingObjective(std::size_t dimension) : dimension_(dimension) {}
  std::size_t dimension() const override { return dimension_; }
  double evaluate(const double* x) override {
    ++calls;
    return Value(x, dimension_);
  }
  std::uint64_t calls = 0;  ///< evaluate() calls so far

 private:
  std::size_t dimension_;
};

using Sphere = CountingObjective<sphere_value>;          ///< see sphere_value
using Rosenbrock = CountingObjective<rosenbrock_value>;  ///< see rosenbrock_value
using Rastrigin = CountingObjective<rastrigin_value>;    ///< see rastrigin_value
using Flat = CountingObjective<flat_value>;              ///< see flat_value
using MostlyNan = CountingObjective<mostly_nan_value>;   ///< see mostly_nan_value

/// A symmetric box [-half_width, half_width]^D, owning its bounds (D <= 16).
struct CubeBox {
  static constexpr std::size_t kMaxDimension = 16;
  double lower[kMaxDimension] = {};
  double upper[kMaxDimension] = {};
  std::size_t dimension = 0;
  CubeBox(std::size_t dim, double half_width) : dimension(dim) {
    for (std::size_t d = 0; d < dim; ++d) {
      lower[d] = -half_width;
      upper[d] = half_width;
    }
  }
  SearchBox view() const {
    return SearchBox{Span<const double>(lower, dimension), Span<const double>(upper, dimension)};
  }
};

}  // namespace hivecal::test
