// The stages of a method on a split dataset (job.hpp): the baseline, the population stages
// (ABC, GSA), LM and the joint-term stages after it, each with its train and test errors.
#include <algorithm>

#include "hivecal/model/rigid_fit.hpp"
#include "hivecal/model/spanning_subset.hpp"
#include "job/job.hpp"

namespace hivecal::detail {
namespace {

/// Copies a population stage's result into the next stage slot.
CalibrationStage& population_stage(Job& job, CalibrationSolver solver, const Paper6StageResult& solved) {
  CalibrationStage& stage = job.result.stages[job.result.stage_count];
  stage.solver = solver;
  stage.params = CalibrationParams::paper;
  stage.model = solved.model;
  stage.base_to_tracker = solved.base_to_tracker;
  stage.evaluations = solved.evaluations;
  stage.iterations = solved.iterations;
  stage.best_cost_m = solved.best_cost_m;
  return stage;
}

/// The positions in the training samples a hybrid's population stage searches on: a
/// spanning subset when there are more than options.population_subset (and the workspace
/// has room), else none (empty: every sample). Chosen in the residual phase's scratch.
Span<const std::uint32_t> population_subset(Job& job) {
  const Span<const Sample> train = job.dataset.train();
  const Span<std::uint32_t> room = job.workspace.subset_room();
  const std::size_t wanted = std::min(job.options.population_subset, room.size());
  if (wanted == 0 || train.size() <= wanted) return Span<const std::uint32_t>();
  const ResidualScratch scratch = job.workspace.open_residuals();
  const std::size_t count =
      spanning_subset(train, job.start.joint_count, scratch.residual_m, Span<std::uint32_t>(room.data(), wanted));
  job.workspace.close();
  return Span<const std::uint32_t>(room.data(), count);
}

/// ABC or GSA on the link lengths from the start geometry, in the workspace's arena; on a
/// spanning subset of the training samples when it starts a hybrid.
Status run_population(Job& job, CalibrationSolver solver, bool hybrid) {
  const CalibrationOptions& o = job.options;
  const Span<const std::uint32_t> subset = hybrid ? population_subset(job) : Span<const std::uint32_t>();
  TraceBase& trace = job.workspace.trace(job.result.stage_count);
  trace.clear();
  Paper6StageResult solved;
  Status status = Status::ok;
  if (solver == CalibrationSolver::abc) {
    AbcOptions abc;
    abc.food_sources = o.abc_food_sources;
    abc.cycles = o.abc_cycles;
    abc.seed = o.seed;
    const CalibrationWorkspaceBase::PopulationPhase phase = job.workspace.open_abc();
    status = calibrate_paper6_abc(job.start, job.dataset.train(), subset, abc, o.paper6_half_width_m, phase.cost,
                                  phase.abc, &solved, &trace, job.observer);
  } else {
    GsaOptions gsa;
    gsa.agents = o.gsa_agents;
    gsa.iterations = o.gsa_iterations;
    gsa.seed = o.seed;
    const CalibrationWorkspaceBase::PopulationPhase phase = job.workspace.open_gsa();
    if (phase.run_gsa == nullptr) return Status::population_out_of_range;  // a workspace without GSA (firmware)
    status = phase.run_gsa(job.start, job.dataset.train(), subset, gsa, o.paper6_half_width_m, phase.cost, phase.gsa,
                           &solved, &trace, job.observer);
  }
  job.workspace.close();
  if (status != Status::ok) return status;
  CalibrationStage& stage = population_stage(job, solver, solved);
  stage.trace_m = trace.values();
  stage.searched_samples = subset.empty() ? job.dataset.train().size() : subset.size();
  return Status::ok;
}

/// Runs one stage with the observer's begin/end around it, then its train/test errors.
/// `hybrid`: the stage is a half of a hybrid (ABC/GSA: the start, on the spanning subset; LM:
/// from the previous stage). `compliance`: the LM+compliance stage (solver lm).
Status run_stage(Job& job, CalibrationSolver solver, bool hybrid, bool compliance = false, bool gravity_only = false) {
  CalibrationResult& r = job.result;
  const std::size_t index = r.stage_count;
  if (job.observer != nullptr) job.observer->on_stage_begin(index, solver);
  const Status status = compliance                        ? run_compliance_lm(job, &r.lm_pruned_mask, gravity_only)
                        : solver == CalibrationSolver::lm ? run_lm(job, hybrid, &r.lm_pruned_mask)
                                                          : run_population(job, solver, hybrid);
  const CalibrationStep step = solver == CalibrationSolver::abc   ? CalibrationStep::abc
                               : solver == CalibrationSolver::gsa ? CalibrationStep::gsa
                                                                  : CalibrationStep::lm;
  if (status != Status::ok) return fail(&r, step, status);
  CalibrationStage& stage = r.stages[index];
  stage.train = position_error_stats(stage.model, stage.base_to_tracker, job.dataset.train());
  stage.test = position_error_stats(stage.model, stage.base_to_tracker, job.dataset.test());
  r.stage_count = index + 1;
  if (job.observer != nullptr) job.observer->on_stage_end(index, stage);
  return Status::ok;
}

/// The tool point and the base fitted together with the nominal joints model (LM over
/// {tool xyz, base 6}, least squares): the reflector offset is rarely known to the millimetre,
/// and a baseline that keeps the guess is not a fair comparison. Below 4 samples (9
/// parameters), the base alone.
Status fit_baseline(const RobotModel& start, Span<const Sample> train, const CalibrationOptions& options,
                    CalibrationWorkspaceBase& workspace, CalibrationResult* r) {
  r->baseline.model = start;  // with several targets, their tool points fitted with the base
  Status status = Status::ok;
  const ParamMask fitted_mask =
      (base_params_mask(start) | tool_params_mask(start)) & ~known_params_mask(options, start);
  const int fitted = mask_count(fitted_mask);
  if (options.base_known) {
    r->baseline.base_to_tracker = options.known_base_to_tracker;
    if (!options.tool_known) fit_other_target_tools(r->baseline.base_to_tracker, train, &r->baseline.model);
  } else {
    status = fit_base_and_target_tools(train, &r->baseline.model, &r->baseline.base_to_tracker);
  }
  if (status != Status::ok || fitted == 0 || 3 * train.size() <= static_cast<std::size_t>(fitted)) return status;
  LmOptions lm;
  lm.params = LmParamSet::custom;
  lm.custom_mask = fitted_mask;
  LmWorkspace* lm_workspace = workspace.open_lm();
  status =
      calibrate_lm(r->baseline.model, &r->baseline.base_to_tracker, train, lm, lm_workspace, &r->lm, nullptr, nullptr);
  workspace.close();
  if (status != Status::ok && status != Status::not_converged) return status;
  r->baseline.model = r->lm.model;
  r->baseline.base_to_tracker = r->lm.base_to_tracker;
  r->baseline.tool_fitted = true;
  return Status::ok;
}

}  // namespace

StagePlan plan_for(CalibrationMethod method) {
  StagePlan plan;
  plan.gsa =
      method == CalibrationMethod::gsa || method == CalibrationMethod::gsa_lm || method == CalibrationMethod::all;
  plan.abc =
      method == CalibrationMethod::abc || method == CalibrationMethod::abc_lm || method == CalibrationMethod::all;
  plan.lm = method == CalibrationMethod::lm || method == CalibrationMethod::abc_lm ||
            method == CalibrationMethod::gsa_lm || method == CalibrationMethod::all;
  plan.hybrid = method == CalibrationMethod::abc_lm || method == CalibrationMethod::gsa_lm;
  return plan;
}

Status fail(CalibrationResult* result, CalibrationStep step, Status status) {
  result->step = step;
  result->status = status;
  return status;
}

void report_phase(CalibrationObserver* observer, CalibrationPhase phase, bool ended) {
  if (observer != nullptr) observer->on_phase(phase, ended);
}

void lm_stage(Job& job, Status status, bool refines_previous, bool compliance, TraceBase& trace) {
  CalibrationResult& r = job.result;
  const CalibrationOptions& o = job.options;
  r.has_lm = true;
  CalibrationStage& stage = r.stages[r.stage_count];
  stage.solver = CalibrationSolver::lm;
  stage.refines_previous = refines_previous;
  stage.compliance = compliance;
  stage.rigid_kept = false;
  stage.holdout = JointTermHoldout{};
  stage.params = o.params;
  stage.status = status;
  stage.model = r.lm.model;
  stage.base_to_tracker = r.lm.base_to_tracker;
  stage.evaluations = static_cast<std::uint64_t>(r.lm.iterations);
  stage.iterations = static_cast<std::size_t>(r.lm.iterations);
  stage.best_cost_m = r.lm.rms_m;
  stage.trace_m = trace.values();
  stage.estimated = r.lm.identifiability.kept_mask;
  stage.residual_sigma_m = r.lm.residual_sigma_m;
}

Status run_lm(Job& job, bool hybrid, ParamMask* pruned) {
  CalibrationResult& r = job.result;
  const CalibrationStage* previous = hybrid && r.stage_count > 0 ? &r.stages[r.stage_count - 1] : nullptr;
  TraceBase& trace = job.workspace.trace(r.stage_count);
  const RobotModel& from = previous != nullptr ? previous->model : job.start;
  const RigidTransform* base = previous != nullptr ? &previous->base_to_tracker : nullptr;
  r.significance_t = choose_significance(job, from, base, previous != nullptr);
  LmFit fit;
  fit.reference = &job.start;
  fit.start_model = &from;
  fit.base = base;
  fit.reset_moved = previous != nullptr;
  fit.samples = job.dataset.train();
  fit.significance_t = r.significance_t;
  const Status status = fit_lm(job, fit, LmFitReport{&trace, job.observer, pruned});
  if (status != Status::ok && status != Status::not_converged) return status;
  lm_stage(job, status, previous != nullptr, false, trace);
  return Status::ok;
}

Status run_split(const RobotModel& start, DatasetBase* dataset, const CalibrationOptions& options,
                 CalibrationWorkspaceBase* workspace, CalibrationResult* r, CalibrationObserver* observer) {
  r->train_count = dataset->train().size();
  r->test_count = dataset->test().size();
  r->train_points = distinct_points(dataset->train());
  report_phase(observer, CalibrationPhase::baseline, false);
  Status status = fit_baseline(start, dataset->train(), options, *workspace, r);
  report_phase(observer, CalibrationPhase::baseline, true);
  if (status != Status::ok) return fail(r, CalibrationStep::baseline, status);
  r->baseline.train = position_error_stats(r->baseline.model, r->baseline.base_to_tracker, dataset->train());
  r->baseline.test = position_error_stats(r->baseline.model, r->baseline.base_to_tracker, dataset->test());
  // The stages start from the baseline's geometry: the start joints with the fitted tool point
  // (ABC / GSA move lengths only and would otherwise keep the tool guess's error).
  Job job{r->baseline.model, start, *dataset, options, *workspace, *r, observer};
  const StagePlan plan = plan_for(options.method);
  if (plan.gsa && (status = run_stage(job, CalibrationSolver::gsa, plan.hybrid)) != Status::ok) return status;
  if (plan.abc && (status = run_stage(job, CalibrationSolver::abc, plan.hybrid)) != Status::ok) return status;
  if (plan.lm && (status = run_stage(job, CalibrationSolver::lm, plan.hybrid)) != Status::ok) return status;
  if (plan.lm && options.compliance.enabled) {
    if (gravity_stage_first(job.start, options.compliance) &&
        (status = run_stage(job, CalibrationSolver::lm, true, true, true)) != Status::ok) {
      return status;
    }
    if ((status = run_stage(job, CalibrationSolver::lm, true, true)) != Status::ok) return status;
  }
  r->step = CalibrationStep::done;
  r->status = Status::ok;
  return Status::ok;
}

}  // namespace hivecal::detail
