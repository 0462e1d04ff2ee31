// Pieces shared by the population solvers (abc.cpp, gsa.cpp): evaluation counting with a
// budget, best-so-far memory, per-iteration reporting and option checks. Internal header.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>

#include "hivecal/solve/objective.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/core/status.hpp"
#include "hivecal/core/trace.hpp"

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

/// The checks every population solver starts with, in this order: validate_population, then
/// validate_search_box. The solver's own option checks follow when this returns ok.
Status validate_population_and_box(std::size_t population, std::size_t capacity, std::uint64_t max_evaluations,
                                   const SearchBox& box, std::size_t dimension, std::size_t max_dimension);

/// Uniform random point in the box (box already validated), one draw per dimension in order.
void random_point_in_box(const SearchBox& box, std::size_t dimension, Random* random, double* x);

/// Pushes the best cost to the trace and calls the observer (either may be null).
void report_iteration(const SolverProgress& progress, TraceBase* trace, ProgressObserver* observer);

/// The result of a run that did nothing (an option error).
SolverResult failed_result(Status status);

/// The result of a completed run: status ok and the best point, its cost and the counts.
SolverResult finished_result(Span<const double> best_x, double best_cost, std::uint64_t evaluations,
                             std::size_t iterations);

/// The frame of a population solver's minimize(): a failed result for invalid options, else
/// count the evaluations, initialise the run, iterate while iterations and budget remain
/// (reporting each) and fill the result. `Run` is built from (storage, counted objective, box,
/// dimension, options) and has initialise(), iterate(1-based iteration) and best_cost().
template <typename Run, typename Storage, typename Options>
Status run_population(Status valid, Objective& objective, const SearchBox& box, std::size_t dimension,
                      const Storage& storage, const Options& options, std::size_t iterations, SolverResult* result,
                      TraceBase* trace, ProgressObserver* progress) {
  if (valid != Status::ok) {
    *result = failed_result(valid);
    return valid;
  }
  CountedObjective counted(objective, options.max_evaluations);
  Run run(storage, &counted, box, dimension, options);
  run.initialise();
  std::size_t iteration = 0;
  while (iteration < iterations && !counted.exhausted()) {
    ++iteration;
    run.iterate(iteration);
    report_iteration(SolverProgress{iteration, iterations, run.best_cost(), counted.count()}, trace, progress);
  }
  *result = finished_result(Span<const double>(storage.best, dimension), run.best_cost(), counted.count(), iteration);
  return Status::ok;
}

}  // namespace hivecal::detail
