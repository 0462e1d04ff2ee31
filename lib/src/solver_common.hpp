// Pieces shared by the population solvers (abc.cpp, gsa.cpp): evaluation counting with a
// budget, best-so-far memory, per-iteration reporting and option checks. Internal header.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>

#include "hivecal/objective.hpp"
#include "hivecal/random.hpp"
#include "hivecal/status.hpp"
#include "hivecal/trace.hpp"

namespace hivecal::detail {

/// Smallest population the solvers accept (ABC needs a neighbour k != i, GSA a second mass).
inline constexpr std::size_t kMinPopulation = 2;

/// An objective seen through an evaluation counter and budget; NaN costs become +Inf so that
/// every comparison orders them last.
class CountedObjective {
 public:
  /// max_evaluations 0 means no cap.
  CountedObjective(Objective& objective, std::uint64_t max_evaluations)
      : objective_(objective), max_evaluations_(max_evaluations) {}
  /// True once the budget is spent: no further evaluate() should be made.
  bool exhausted() const { return max_evaluations_ != 0 && count_ >= max_evaluations_; }
  /// The cost at x (NaN mapped to +Inf); counts one evaluation.
  double evaluate(const double* x);
  std::uint64_t count() const { return count_; }  ///< evaluations made

 private:
  Objective& objective_;
  std::uint64_t max_evaluations_;
  std::uint64_t count_ = 0;
};

/// The best point seen so far, copied into caller storage of `dimension` doubles.
class BestSoFar {
 public:
  BestSoFar(double* x, std::size_t dimension) : x_(x), dimension_(dimension) {}
  /// Keeps `point` if it is the first offer or strictly better than the best so far.
  void offer(const double* point, double cost);
  double cost() const { return cost_; }  ///< best cost so far (+Inf before any offer)

 private:
  double* x_;
  std::size_t dimension_;
  double cost_ = std::numeric_limits<double>::infinity();
  bool any_ = false;
};

/// Checks the population against the solver's capacity (population_out_of_range) and the
/// evaluation budget against the initial population (invalid_argument).
Status validate_population(std::size_t population, std::size_t capacity, std::uint64_t max_evaluations);

/// Uniform random point in the box (box already validated), one draw per dimension in order.
void random_point_in_box(const SearchBox& box, std::size_t dimension, Random* random, double* x);

/// Pushes the best cost to the trace and calls the observer (either may be null).
void report_iteration(const SolverProgress& progress, TraceBase* trace, ProgressObserver* observer);

/// The result of a run that did nothing (an option error).
SolverResult failed_result(Status status);

}  // namespace hivecal::detail
