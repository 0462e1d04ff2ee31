#include "hivecal/calibration.hpp"

#include <new>

#include "hivecal/model/rigid_fit.hpp"

namespace hivecal {
namespace {

/// Which stages a method runs.
struct StagePlan {
  bool gsa = false;     ///< GSA on the link lengths
  bool abc = false;     ///< ABC on the link lengths
  bool lm = false;      ///< LM
  bool hybrid = false;  ///< LM starts from the population stage's result
};

StagePlan plan_for(CalibrationMethod method) {
  StagePlan plan;
  plan.gsa = method == CalibrationMethod::gsa || method == CalibrationMethod::gsa_lm || method == CalibrationMethod::all;
  plan.abc = method == CalibrationMethod::abc || method == CalibrationMethod::abc_lm || method == CalibrationMethod::all;
  plan.lm = method == CalibrationMethod::lm || method == CalibrationMethod::abc_lm ||
            method == CalibrationMethod::gsa_lm || method == CalibrationMethod::all;
  plan.hybrid = method == CalibrationMethod::abc_lm || method == CalibrationMethod::gsa_lm;
  return plan;
}

bool known(const CalibrationOptions& options) {
  return options.method <= CalibrationMethod::all && options.params <= CalibrationParams::paper;
}

/// The job's state while it runs: the inputs and where the result goes.
struct Job {
  const RobotModel& start;
  const DatasetBase& dataset;
  const CalibrationOptions& options;
  CalibrationWorkspaceBase& workspace;
  CalibrationResult& result;
  CalibrationObserver* observer;
};

Status fail(CalibrationResult* result, CalibrationStep step, Status status) {
  result->step = step;
  result->status = status;
  return status;
}

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

/// ABC or GSA on the link lengths from the start geometry, in the workspace's arena.
Status run_population(Job& job, CalibrationSolver solver) {
  const CalibrationOptions& o = job.options;
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
    status = calibrate_paper6_abc(job.start, job.dataset.train(), abc, o.paper6_half_width_m, phase.cost, phase.abc,
                                  &solved, &trace, job.observer);
  } else {
    GsaOptions gsa;
    gsa.agents = o.gsa_agents;
    gsa.iterations = o.gsa_iterations;
    gsa.seed = o.seed;
    const CalibrationWorkspaceBase::PopulationPhase phase = job.workspace.open_gsa();
    status = calibrate_paper6_gsa(job.start, job.dataset.train(), gsa, o.paper6_half_width_m, phase.cost, phase.gsa,
                                  &solved, &trace, job.observer);
  }
  job.workspace.close();
  if (status != Status::ok) return status;
  population_stage(job, solver, solved).trace_m = trace.values();
  return Status::ok;
}

/// LM from the start geometry, or (hybrid) from the previous stage's geometry and base.
Status run_lm(Job& job, bool hybrid) {
  const CalibrationOptions& o = job.options;
  CalibrationResult& r = job.result;
  const CalibrationStage* previous = hybrid && r.stage_count > 0 ? &r.stages[r.stage_count - 1] : nullptr;
  LmOptions lm = o.lm;
  lm.params = o.params == CalibrationParams::paper ? LmParamSet::link_lengths : LmParamSet::full;
  lm.loss = o.robust ? LmLoss::huber : LmLoss::squared;
  TraceBase& trace = job.workspace.trace(r.stage_count);
  trace.clear();
  LmWorkspace* workspace = job.workspace.open_lm();
  const Status status = calibrate_lm(previous != nullptr ? previous->model : job.start,
                                     previous != nullptr ? &previous->base_to_tracker : nullptr, job.dataset.train(),
                                     lm, workspace, &r.lm, &trace, job.observer);
  job.workspace.close();
  if (status != Status::ok && status != Status::not_converged) return status;
  r.has_lm = true;
  CalibrationStage& stage = r.stages[r.stage_count];
  stage.solver = CalibrationSolver::lm;
  stage.refines_previous = previous != nullptr;
  stage.params = o.params;
  stage.status = status;
  stage.model = r.lm.model;
  stage.base_to_tracker = r.lm.base_to_tracker;
  stage.evaluations = static_cast<std::uint64_t>(r.lm.iterations);
  stage.iterations = static_cast<std::size_t>(r.lm.iterations);
  stage.best_cost_m = r.lm.rms_m;
  stage.trace_m = trace.values();
  return Status::ok;
}

/// Runs one stage with the observer's begin/end around it, then its train/test errors.
Status run_stage(Job& job, CalibrationSolver solver, bool hybrid) {
  CalibrationResult& r = job.result;
  const std::size_t index = r.stage_count;
  if (job.observer != nullptr) job.observer->on_stage_begin(index, solver);
  const Status status = solver == CalibrationSolver::lm ? run_lm(job, hybrid) : run_population(job, solver);
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

/// Input checks, split and baseline: everything before the first solver.
Status prepare(const RobotModel& start, DatasetBase* dataset, const CalibrationOptions& options,
               CalibrationResult* r) {
  if (!known(options)) return fail(r, CalibrationStep::input, Status::invalid_argument);
  if (dataset->size() == 0) return fail(r, CalibrationStep::input, Status::dataset_empty);
  if (dataset->size() < calibration_minimum_samples(options.params)) {
    return fail(r, CalibrationStep::input, Status::too_few_samples);
  }
  Status status = dataset->split(options.train_fraction, options.seed);
  if (status != Status::ok) return fail(r, CalibrationStep::split, status);
  r->train_count = dataset->train().size();
  r->test_count = dataset->test().size();
  r->baseline.model = start;  // with several targets, their tool points fitted (the stages start here)
  status = fit_base_and_target_tools(dataset->train(), &r->baseline.model, &r->baseline.base_to_tracker);
  if (status != Status::ok) return fail(r, CalibrationStep::baseline, status);
  r->baseline.train = position_error_stats(r->baseline.model, r->baseline.base_to_tracker, dataset->train());
  r->baseline.test = position_error_stats(r->baseline.model, r->baseline.base_to_tracker, dataset->test());
  return Status::ok;
}

}  // namespace

const char* calibration_method_name(CalibrationMethod method) {
  switch (method) {
    case CalibrationMethod::lm: return "lm";
    case CalibrationMethod::abc: return "abc";
    case CalibrationMethod::gsa: return "gsa";
    case CalibrationMethod::abc_lm: return "abc+lm";
    case CalibrationMethod::gsa_lm: return "gsa+lm";
    case CalibrationMethod::all: return "all";
  }
  return "unknown";
}

std::size_t calibration_minimum_samples(CalibrationParams params) {
  // Three equations per sample: 12 samples give 36 for the paper's 6 lengths + 6 base
  // parameters, 24 give 72 for the ~24 the full model identifies + 6 base. LM itself only
  // refuses 3 N <= free parameters; below these a fit is mostly noise.
  return params == CalibrationParams::paper ? 12 : 24;
}

const char* calibration_solver_name(CalibrationSolver solver) {
  switch (solver) {
    case CalibrationSolver::abc: return "ABC";
    case CalibrationSolver::gsa: return "GSA";
    case CalibrationSolver::lm: return "LM";
  }
  return "unknown";
}

const char* calibration_stage_name(const CalibrationStage& stage, const CalibrationStage* previous) {
  if (stage.solver != CalibrationSolver::lm || !stage.refines_previous || previous == nullptr) {
    return calibration_solver_name(stage.solver);
  }
  return previous->solver == CalibrationSolver::abc ? "ABC+LM" : "GSA+LM";
}

const char* calibration_step_name(CalibrationStep step) {
  switch (step) {
    case CalibrationStep::input: return "input";
    case CalibrationStep::split: return "split";
    case CalibrationStep::baseline: return "baseline";
    case CalibrationStep::gsa: return "gsa";
    case CalibrationStep::abc: return "abc";
    case CalibrationStep::lm: return "lm";
    case CalibrationStep::done: return "done";
  }
  return "unknown";
}

Status calibrate(const RobotModel& start, DatasetBase* dataset, const CalibrationOptions& options,
                 CalibrationWorkspaceBase* workspace, CalibrationResult* result, CalibrationObserver* observer) {
  if (result == nullptr) return Status::invalid_argument;
  result->~CalibrationResult();
  CalibrationResult& r = *new (result) CalibrationResult();  // in place: no 5 KB temporary on the stack
  if (dataset == nullptr || workspace == nullptr) return fail(&r, CalibrationStep::input, Status::invalid_argument);
  Status status = prepare(start, dataset, options, &r);
  if (status != Status::ok) return status;
  Job job{r.baseline.model, *dataset, options, *workspace, r, observer};
  const StagePlan plan = plan_for(options.method);
  if (plan.gsa && (status = run_stage(job, CalibrationSolver::gsa, false)) != Status::ok) return status;
  if (plan.abc && (status = run_stage(job, CalibrationSolver::abc, false)) != Status::ok) return status;
  if (plan.lm && (status = run_stage(job, CalibrationSolver::lm, plan.hybrid)) != Status::ok) return status;
  r.step = CalibrationStep::done;
  r.status = Status::ok;
  return Status::ok;
}

}  // namespace hivecal
