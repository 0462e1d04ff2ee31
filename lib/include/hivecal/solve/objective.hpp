// What the population solvers (ABC, GSA) optimise and report: a D-dimensional cost over a
// box, a result, and an optional per-iteration progress hook. No heap, no OS.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/core/status.hpp"
#include "hivecal/core/types.hpp"

namespace hivecal {

/// A cost to minimise over a box in R^dimension(). Implementations may keep state
/// (caches, counters), hence evaluate() is not const.
class Objective {
 public:
  /// Number of parameters the cost takes.
  virtual std::size_t dimension() const = 0;
  /// Cost at x[0 .. dimension()); NaN is treated by the solvers as +Inf (worst).
  virtual double evaluate(const double* x) = 0;

 protected:
  Objective() = default;
  Objective(const Objective&) = default;
  Objective& operator=(const Objective&) = default;
  ~Objective() = default;
};

/// Box bounds lower[d] < upper[d] (both finite), in the objective's units.
struct SearchBox {
  Span<const double> lower;  ///< lower bound per parameter [objective's units]
  Span<const double> upper;  ///< upper bound per parameter [objective's units]
};

/// Checks a box against a dimension and a capacity. Errors: dimension_out_of_range (0, above
/// max_dimension, or a bound count different from dimension), bad_bounds (NaN/Inf or lower >= upper).
Status validate_search_box(const SearchBox& box, std::size_t dimension, std::size_t max_dimension);

/// Where a solver is after one iteration (what ProgressObserver receives).
struct SolverProgress {
  std::size_t iteration = 0;        ///< iterations done, 1 .. iteration_count
  std::size_t iteration_count = 0;  ///< iterations planned
  double best_cost = 0.0;           ///< best cost so far [objective's units]
  std::uint64_t evaluations = 0;    ///< cost evaluations so far
};

/// Optional hook called once per solver iteration (e.g. to print progress or feed a watchdog).
class ProgressObserver {
 public:
  /// Called after each iteration, after the trace was updated.
  virtual void on_iteration(const SolverProgress& progress) = 0;

 protected:
  ProgressObserver() = default;
  ProgressObserver(const ProgressObserver&) = default;
  ProgressObserver& operator=(const ProgressObserver&) = default;
  ~ProgressObserver() = default;
};

/// What a population solver returns. best_x views the solver's own storage: valid until
/// the solver runs again or is destroyed.
struct SolverResult {
  Status status = Status::invalid_argument;  ///< ok, or why nothing was run
  Span<const double> best_x;                 ///< best parameters found [objective's units]
  double best_cost = 0.0;                    ///< cost at best_x [objective's units]
  std::uint64_t evaluations = 0;             ///< cost evaluations made
  std::size_t iterations = 0;                ///< iterations completed
};

}  // namespace hivecal
