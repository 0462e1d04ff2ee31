#include "hivecal/solve/population_stage.hpp"

#include "hivecal/solve/cost.hpp"

namespace hivecal {
namespace {

/// The common part of both population stages; `minimize` runs the solver on (cost, box).
template <typename Minimize>
Status run_paper6_stage(const RobotModel& start, Span<const Sample> train, Span<const std::uint32_t> subset,
                        double half_width_m, Paper6CostBase* cost, Paper6StageResult* result, Minimize minimize) {
  if (cost == nullptr || result == nullptr) return Status::invalid_argument;
  Status status = cost->build(start, train, subset);
  if (status != Status::ok) return status;
  LinkLengthBox box;
  status = link_length_box(start, half_width_m, &box);
  if (status != Status::ok) return status;
  SolverResult solved;
  status = minimize(box.view(), &solved);
  if (status != Status::ok) return status;
  Paper6StageResult out;
  out.model = cost->model_for(solved.best_x.data());
  out.best_cost_m = solved.best_cost;
  out.evaluations = solved.evaluations;
  out.iterations = solved.iterations;
  status = fit_base_to_tracker(out.model, train, &out.base_to_tracker);
  if (status != Status::ok) return status;
  *result = out;
  return Status::ok;
}

/// A population stage with `solver` (ABC or GSA, each with its options type).
template <typename Solver, typename Options>
Status run_population_stage(const RobotModel& start, Span<const Sample> train, Span<const std::uint32_t> subset,
                            const Options& options, double half_width_m, Paper6CostBase* cost, Solver* solver,
                            Paper6StageResult* result, TraceBase* trace, ProgressObserver* progress) {
  if (solver == nullptr) return Status::invalid_argument;
  return run_paper6_stage(start, train, subset, half_width_m, cost, result,
                          [&](const SearchBox& box, SolverResult* solved) {
                            return solver->minimize(*cost, box, options, solved, trace, progress);
                          });
}

}  // namespace

Status calibrate_paper6_abc(const RobotModel& start, Span<const Sample> train, Span<const std::uint32_t> subset,
                            const AbcOptions& options, double half_width_m, Paper6CostBase* cost, AbcSolverBase* solver,
                            Paper6StageResult* result, TraceBase* trace, ProgressObserver* progress) {
  return run_population_stage(start, train, subset, options, half_width_m, cost, solver, result, trace, progress);
}

Status calibrate_paper6_gsa(const RobotModel& start, Span<const Sample> train, Span<const std::uint32_t> subset,
                            const GsaOptions& options, double half_width_m, Paper6CostBase* cost, GsaSolverBase* solver,
                            Paper6StageResult* result, TraceBase* trace, ProgressObserver* progress) {
  return run_population_stage(start, train, subset, options, half_width_m, cost, solver, result, trace, progress);
}

}  // namespace hivecal
