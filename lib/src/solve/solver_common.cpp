#include "solve/solver_common.hpp"

#include <limits>

#include "hivecal/core/math.hpp"

namespace hivecal {

Status validate_search_box(const SearchBox& box, std::size_t dimension, std::size_t max_dimension) {
  if (dimension == 0 || dimension > max_dimension) return Status::dimension_out_of_range;
  if (box.lower.size() != dimension || box.upper.size() != dimension) return Status::dimension_out_of_range;
  for (std::size_t d = 0; d < dimension; ++d) {
    const double lower = box.lower[d];
    const double upper = box.upper[d];
    if (!math::is_finite(lower) || !math::is_finite(upper) || !(lower < upper)) return Status::bad_bounds;
  }
  return Status::ok;
}

namespace detail {

double CountedObjective::evaluate(const double* x) {
  ++count_;
  const double cost = objective_.evaluate(x);
  return cost == cost ? cost : std::numeric_limits<double>::infinity();
}

void BestSoFar::offer(const double* point, double cost) {
  if (any_ && !(cost < cost_)) return;
  any_ = true;
  cost_ = cost;
  for (std::size_t d = 0; d < dimension_; ++d) x_[d] = point[d];
}

Status validate_population(std::size_t population, std::size_t capacity, std::uint64_t max_evaluations) {
  if (population < kMinPopulation || population > capacity) return Status::population_out_of_range;
  if (max_evaluations != 0 && max_evaluations < population) return Status::invalid_argument;
  return Status::ok;
}

Status validate_population_and_box(std::size_t population, std::size_t capacity, std::uint64_t max_evaluations,
                                   const SearchBox& box, std::size_t dimension, std::size_t max_dimension) {
  const Status population_status = validate_population(population, capacity, max_evaluations);
  if (population_status != Status::ok) return population_status;
  return validate_search_box(box, dimension, max_dimension);
}

void random_point_in_box(const SearchBox& box, std::size_t dimension, Random* random, double* x) {
  for (std::size_t d = 0; d < dimension; ++d) x[d] = random->uniform(box.lower[d], box.upper[d]);
}

void report_iteration(const SolverProgress& progress, TraceBase* trace, ProgressObserver* observer) {
  if (trace != nullptr) trace->push(progress.best_cost);
  if (observer != nullptr) observer->on_iteration(progress);
}

SolverResult failed_result(Status status) {
  SolverResult result;
  result.status = status;
  return result;
}

SolverResult finished_result(Span<const double> best_x, double best_cost, std::uint64_t evaluations,
                             std::size_t iterations) {
  SolverResult result;
  result.status = Status::ok;
  result.best_x = best_x;
  result.best_cost = best_cost;
  result.evaluations = evaluations;
  result.iterations = iterations;
  return result;
}

}  // namespace detail
}  // namespace hivecal
