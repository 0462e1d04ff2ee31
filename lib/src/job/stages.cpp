// The stages of a method on a split dataset (job.hpp): the baseline, the population stages
// (ABC, GSA), LM and the joint-term stages after it, each with its train and test errors; one
// LM fit of the job with its significance test (what LM may move, the parameters LM dropped or
// an earlier stage moved put back, the joint terms and, on a small set, the geometry fixed one
// at a time while a change is not significant) and the left-out poses (the level chosen on
// them, a joint-term stage's terms checked on them).
#include <algorithm>
#include <cmath>

#include "hivecal/model/rigid_fit.hpp"
#include "hivecal/model/spanning_subset.hpp"
#include "job/blocked_folds.hpp"
#include "job/blunder_search.hpp"
#include "job/job.hpp"
#include "job/term_elimination.hpp"

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
  stage.prior_tolerances = LmPriorTolerances{};  // no prior on a population search
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
/// from the previous stage). `compliance`: a joint-term stage (solver lm) of the families `families`.
Status run_stage(Job& job, CalibrationSolver solver, bool hybrid, bool compliance = false,
                 JointTermFamilySet families = 0) {
  CalibrationResult& r = job.result;
  const std::size_t index = r.stage_count;
  if (job.observer != nullptr) job.observer->on_stage_begin(index, solver);
  const Status status = compliance                        ? run_compliance_lm(job, &r.lm_pruned_mask, families)
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

// Helpers marked [[gnu::noinline]] hold large temporaries (parameter vectors, fit
// accumulators) while the LM solve below their caller does not need them: inlined, their
// frames would stay live during LM and add ~3 kB to the firmware's 8 kB stack peak.

/// *model rebuilt from `params` with its compliance terms and (keep_other_tools: a known
/// tool, which LM never moves) its other targets' tool points; else those restart at 0, as
/// they always have (LM estimates them again).
void set_params(const ModelParams& params, bool keep_other_tools, RobotModel* model) {
  set_model_params(params, model);
  for (int t = 1; !keep_other_tools && t < kMaxTargets; ++t) target_tool(model, t) = Vec3::Zero();
}

/// True when LM dropped a model parameter that `from` holds at another value than `start`:
/// an earlier stage moved a parameter the data cannot determine. Such ones are put back to
/// their start values in *from.
[[gnu::noinline]] bool reset_dropped(const RobotModel& start, const IdentifiabilityReport& report,
                                     bool keep_other_tools, RobotModel* from) {
  const ModelParams start_params = to_params(start);
  ModelParams params = to_params(*from);
  bool changed = false;
  for (int i = 0; i < model_param_count(start); ++i) {
    if (mask_has(report.free_mask, i) && !mask_has(report.kept_mask, i) && params(i) != start_params(i)) {
      params(i) = start_params(i);
      changed = true;
    }
  }
  bool compliance_changed = false;
  for (int t = 0; t < from->compliance.term_count; ++t) {  // the compliance coefficients likewise
    const int i = compliance_param_index(*from, t);
    double& coefficient = from->compliance.coefficient[t];
    if (mask_has(report.free_mask, i) && !mask_has(report.kept_mask, i) &&
        coefficient != start.compliance.coefficient[t]) {
      coefficient = start.compliance.coefficient[t];
      compliance_changed = true;
    }
  }
  if (changed) set_params(params, keep_other_tools, from);
  return changed || compliance_changed;
}

/// Puts parameter `index` (geometry or compliance) of *model back to its value in `start`.
[[gnu::noinline]] void reset_param(const RobotModel& start, int index, bool keep_other_tools, RobotModel* model) {
  const int rigid_count = rigid_param_count(start);
  if (index >= rigid_count) {
    model->compliance.coefficient[index - rigid_count] = start.compliance.coefficient[index - rigid_count];
    return;
  }
  ModelParams params = to_params(*model);
  params(index) = to_params(start)(index);
  set_params(params, keep_other_tools, model);
}

/// Whether fit_lm's significance test covers the geometry of a rigid fit of `samples` whose first
/// attempt is `first`: on every set when the options ask for it, else on a small set only (fewer
/// distinct configurations than kSignificancePosesPerParam per rigid parameter estimated). Records the decision
/// and the counts in *r (as r->lm, the last fit's); the joint-term stages keep it.
bool tests_geometry(const CalibrationOptions& o, Span<const Sample> samples, const LmResult& first,
                    CalibrationResult* r) {
  static_assert(kSignificancePosesPerParam * kMaxRigidParamCount < kDistinctPointLimit,
                "the count must reach the bound");
  r->significance_poses = distinct_configurations(samples);
  r->significance_params =
      static_cast<std::size_t>(mask_count(first.identifiability.kept_mask & rigid_params_mask(first.model)));
  r->geometry_tested =
      o.significance_every_set || static_cast<double>(r->significance_poses) <
                                      kSignificancePosesPerParam * static_cast<double>(r->significance_params);
  return r->geometry_tested;
}

/// The estimated model parameter (geometry or joint-term coefficient) whose change from
/// `start` is least significant, below t standard deviations (a joint term: below its level
/// >= t, its family's in `start` from `compliance_t` (joint_term_levels), its ratio scaled by
/// t / level to compare); -1 when none is (or t <= 0). The joint terms
/// are tried first, the geometry (when `geometry`) only when every estimated term clears its level: a new term
/// must earn its place, never take a geometry parameter's. (Tried together, a joint's offset,
/// whose sigma a free harmonic sum inflates, would go first, and the sum of sin q, cos 2q and
/// sin 3q, flat over a joint's turn of +-1 rad, would take the offset's place at 20 sigma.)
[[gnu::noinline]] int least_significant(const RobotModel& start, const LmResult& lm, double t, double compliance_t,
                                        bool geometry) {
  if (!(t > 0.0)) return -1;
  const JointTermLevels levels = joint_term_levels(start, compliance_t, lm.residual_dof);
  const ModelParams change = to_params(lm.model) - to_params(start);
  const int model_count = model_param_count(lm.model);
  const int rigid_count = rigid_param_count(lm.model);
  int weakest = -1;
  double weakest_ratio = t;
  const auto consider = [&](int i) {
    if (!mask_has(lm.identifiability.kept_mask, i) || !(lm.sigma(i) > 0.0)) return;
    const double delta = i < model_count ? change(i) : full_param_value(lm.model, i) - full_param_value(start, i);
    const double level = levels.of(i);
    const double ratio =
        i < rigid_count ? std::fabs(delta) / lm.sigma(i) : std::fabs(delta) / lm.sigma(i) * (t / std::fmax(t, level));
    if (ratio < weakest_ratio) {
      weakest_ratio = ratio;
      weakest = i;
    }
  };
  for (int i = rigid_count; i < rigid_count + lm.model.compliance.term_count; ++i) consider(i);
  if (weakest >= 0 || !geometry) return weakest;
  for (int i = 0; i < model_count; ++i) consider(i);  // the base is not a model parameter
  return weakest;
}

/// The estimated joint term of r.lm's fit whose coefficient is largest beyond
/// kMaxJointTermCoefficient (not a robot's: the terms took up something else); -1 when none is.
int implausible_joint_term(const LmResult& lm) {
  int worst = -1;
  double worst_abs = kMaxJointTermCoefficient;
  for (int t = 0; t < lm.model.compliance.term_count; ++t) {
    const int index = compliance_param_index(lm.model, t);
    const double magnitude = std::fabs(lm.model.compliance.coefficient[t]);
    if (!mask_has(lm.identifiability.kept_mask, index) || magnitude <= worst_abs) continue;  // NaN: picked
    worst_abs = magnitude;
    worst = index;
  }
  return worst;
}

/// Joint terms a stage tests from which the test's fixes after the first are made on the
/// linearised fit (term_elimination.hpp): below, a refit per fix is as cheap, and a build that
/// holds fewer terms (the firmware's 4) leaves that code out [-].
constexpr int kLinearisedFixesMinTerms = 5;

/// Whether the test of `reference`'s joint terms makes its fixes on the linearised fit.
constexpr bool linearised_fixes(const RobotModel& reference) {
  return kMaxComplianceTerms >= kLinearisedFixesMinTerms && reference.compliance.term_count >= kLinearisedFixesMinTerms;
}

/// Candidate significance levels of the automatic choice, from the simplest model down [-].
constexpr double kSignificanceGrid[] = {3.0, 2.0, 1.0, 0.0};

/// Whether training sample i is the first of its pose (same_pose).
bool first_of_its_pose(Span<const Sample> train, std::size_t i) {
  for (std::size_t j = 0; j < i; ++j) {
    if (same_pose(train[j], train[i])) return false;
  }
  return true;
}

/// Moves the first n samples' ones at the pose of `pose` (same_pose: every target) to the end of
/// the n, each with one exchange; moved[m] receives the position the m-th exchange took it from,
/// so that put_pose_back restores the order. Returns how many moved [-].
std::size_t move_pose_to_end(DatasetBase& dataset, std::size_t n, const Sample& pose, std::uint8_t* moved) {
  std::size_t count = 0;
  for (std::size_t i = n; i-- > 0;) {  // from the end: a moved sample is never visited again
    if (!same_pose(dataset.samples()[i], pose)) continue;
    dataset.swap_samples(i, n - 1 - count);
    moved[count++] = static_cast<std::uint8_t>(i);
  }
  return count;
}

/// Undoes move_pose_to_end: the exchanges in reverse order.
void put_pose_back(DatasetBase& dataset, std::size_t n, const std::uint8_t* moved, std::size_t count) {
  while (count-- > 0) dataset.swap_samples(moved[count], n - 1 - count);
}

/// Sum of the 3-D errors of `samples` under r.lm's fit [m].
double left_out_error_sum_m(const LmResult& lm, Span<const Sample> samples) {
  double sum_m = 0.0;
  for (const Sample& s : samples) sum_m += (lm.base_to_tracker.apply(fk_sample_point(lm.model, s)) - s.point_m).norm();
  return sum_m;
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
  stage.prior_tolerances = r.lm.prior_tolerances;
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
  if (plan.lm && options.compliance.enabled) {  // the joint-term stages, a family at a time
    const JointTermStages stages = joint_term_stages(job.start, options.compliance);
    for (int k = 0; k < stages.count; ++k) {
      if ((status = run_stage(job, CalibrationSolver::lm, true, true, stages.families[k])) != Status::ok) return status;
    }
  }
  r->step = CalibrationStep::done;
  r->status = Status::ok;
  return Status::ok;
}

ParamMask tool_params_mask(const RobotModel& model) {
  ParamMask mask = 0;
  for (int axis = 0; axis < 3; ++axis) mask |= param_bit(tool_param_index(model, axis));
  return mask;
}

ParamMask base_params_mask(const RobotModel& model) {
  ParamMask mask = 0;
  for (int axis = 0; axis < 3; ++axis) {
    mask |= param_bit(base_rotation_param_index(model, axis)) | param_bit(base_translation_param_index(model, axis));
  }
  return mask;
}

ParamMask known_params_mask(const CalibrationOptions& options, const RobotModel& model) {
  return (options.base_known ? base_params_mask(model) : 0) | (options.tool_known ? tool_params_mask(model) : 0);
}

Status fit_lm(Job& job, const LmFit& fit, const LmFitReport& report) {
  const RobotModel& reference = *fit.reference;
  const bool compliance = fit.compliance;
  const RigidTransform* base = fit.base;
  TraceBase* trace = report.trace;
  ParamMask* pruned = report.pruned;
  RobotModel& from = job.workspace.lm_start();  // start_model is never this one: a stage's or the job's model
  RigidTransform warm_base;                     // the base a warm start or a next attempt starts from
  if (fit.warm) {                               // where the last fit ended (r.lm, which LM clears: copied first)
    from = job.result.lm.model;
    warm_base = job.result.lm.base_to_tracker;
    base = &warm_base;
  } else {
    from = *fit.start_model;
  }
  // LM+compliance: the start terms on the fitted geometry (a warm start keeps its coefficients
  // but those it now holds fixed).
  if (compliance && !fit.warm) from.compliance = reference.compliance;
  for (int t = 0; fit.warm && t < reference.compliance.term_count; ++t) {
    if (mask_has(fit.fixed_terms, compliance_param_index(reference, t))) {
      from.compliance.coefficient[t] = reference.compliance.coefficient[t];
    }
  }
  const CalibrationOptions& o = job.options;
  CalibrationResult& r = job.result;
  LmOptions lm = o.lm;
  lm.params = o.params == CalibrationParams::paper ? LmParamSet::link_lengths
              : compliance                         ? LmParamSet::full_compliance
                                                   : LmParamSet::full;
  if (o.params == CalibrationParams::paper && r.baseline.tool_fitted) {
    // The tool point is estimated too: it was not known (the baseline fitted it), and lengths
    // searched against a tool fitted at the nominal lengths keep that fit's bias.
    lm.custom_mask = lm_param_mask(LmParamSet::link_lengths, 0, reference) | tool_params_mask(reference);
    lm.params = LmParamSet::custom;
  }
  if (o.params == CalibrationParams::paper && compliance) {
    lm.custom_mask = lm_param_mask(lm.params, lm.custom_mask, reference) | compliance_params_mask(reference);
    lm.params = LmParamSet::custom;
  }
  lm.loss = o.robust ? LmLoss::huber : LmLoss::squared;
  lm.prior = detail::job_lm_prior(job.nominal, o.prior);
  if (o.base_known || o.tool_known) {  // the base / the tool points stay where the options put them
    if (o.base_known) base = &o.known_base_to_tracker;
    lm.custom_mask = lm_param_mask(lm.params, lm.custom_mask, reference) & ~known_params_mask(o, reference);
    lm.params = LmParamSet::custom;
  }
  if (fit.fixed_terms != 0) {
    lm.custom_mask = lm_param_mask(lm.params, lm.custom_mask, reference) & ~fit.fixed_terms;
    lm.params = LmParamSet::custom;
  }
  const ParamMask free_mask = lm_param_mask(lm.params, lm.custom_mask, reference);
  // The other targets' tool points are free whenever the stage estimates the tool point, also
  // after the significance test fixed tool_x (else they would stay at their start values).
  for (int axis = 0; axis < 3; ++axis) {
    lm.other_target_tools |= mask_has(free_mask, tool_param_index(reference, axis));
  }
  Status status = Status::ok;
  *pruned = 0;
  bool geometry = r.geometry_tested;  // a joint-term stage: the rigid stage's; a rigid one decides below
  // Each attempt fixes one parameter at most: the geometry and the model's joint terms (not the
  // capacity's: the same attempts on every build).
  const int attempts = model_param_count(reference) + reference.compliance.term_count + 2;
  for (int attempt = 0; attempt < attempts; ++attempt) {
    if (trace != nullptr) trace->clear();
    LmWorkspace* workspace = job.workspace.open_lm();
    status = calibrate_lm(from, base, fit.samples, lm, workspace, &r.lm, trace, report.observer);
    job.workspace.close();
    if (status != Status::ok && status != Status::not_converged) return status;
    // A next attempt starts where this one ended, with what it puts back at the reference values:
    // a few iterations instead of a fit from the stage's start.
    from = r.lm.model;
    warm_base = r.lm.base_to_tracker;
    base = &warm_base;
    // The other targets' tool points stay where this attempt put them (the next one starts there).
    bool again = reset_dropped(reference, r.lm.identifiability, true, &from) && fit.reset_moved;
    int weakest = implausible_joint_term(r.lm);
    if (attempt == 0 && !compliance) geometry = tests_geometry(o, fit.samples, r.lm, &r);
    if (weakest < 0)
      weakest = least_significant(reference, r.lm, fit.significance_t, o.compliance.significance_t, geometry);
    ParamMask fixes = weakest >= 0 ? param_bit(weakest) : ParamMask{0};
    if (compliance && weakest >= rigid_param_count(reference) && linearised_fixes(reference)) {
      // The terms the test would fix after this one, each after a refit: on the linearised
      // fit at once (the refit below then takes them all).
      const bool other_tools =
          (lm.other_target_tools || mask_has(r.lm.identifiability.kept_mask, tool_param_index(reference, 0)));
      const FoldFit fitted{&r.lm.model, &r.lm.base_to_tracker,
                           r.lm.identifiability.kept_mask | (other_tools ? kOtherTargetTools : ParamMask{0}),
                           detail::job_lm_prior(job.nominal, r.lm.prior_tolerances),
                           r.lm.residual_sigma_m * r.lm.residual_sigma_m};
      ParamMask linearised = 0;
      if (linearised_term_fixes(fitted, reference, fit.samples, blunder_test_loss(o), weakest, fit.significance_t,
                                o.compliance.significance_t, r.lm.residual_sigma_m, r.lm.residual_dof, job.workspace,
                                &linearised) == Status::ok) {
        fixes |= linearised;
      }
    }
    if (fixes != 0) {
      *pruned |= fixes;
      lm.params = LmParamSet::custom;
      lm.custom_mask = free_mask & ~*pruned;
      for (int i = 0; i < kFullParamCount; ++i) {
        if (mask_has(fixes, i)) reset_param(reference, i, true, &from);
      }
      again = true;
    }
    if (!again) break;
  }
  return status;
}

[[gnu::noinline]] double choose_significance(Job& job, const RobotModel& from, const RigidTransform* base, bool reset) {
  const double t = job.options.significance_t;
  const std::size_t n = job.dataset.train().size();
  if (t >= 0.0) return t;
  if (n > kAutoSignificanceMaxSamples || n < 3) return kDefaultSignificance;
  static_assert(kAutoSignificanceMaxSamples <= 256, "move_pose_to_end records positions in a byte");
  std::uint8_t moved[kAutoSignificanceMaxSamples];
  double best_t = kDefaultSignificance;
  double best_mae_m = 0.0;
  bool found = false;
  for (double candidate : kSignificanceGrid) {
    double sum_m = 0.0;
    bool ok = true;
    for (std::size_t i = 0; ok && i < n; ++i) {
      if (!first_of_its_pose(job.dataset.train(), i)) continue;
      const Sample pose = job.dataset.train()[i];                               // a copy: the move reorders the samples
      const std::size_t count = move_pose_to_end(job.dataset, n, pose, moved);  // the left-out pose last
      ok = count < n;
      if (ok) {
        ParamMask pruned = 0;
        LmFit fit;
        fit.reference = &job.start;
        fit.start_model = &from;
        fit.base = base;
        fit.reset_moved = reset;
        fit.samples = job.dataset.train().subspan(0, n - count);
        fit.significance_t = candidate;
        LmFitReport report;
        report.pruned = &pruned;
        const Status status = fit_lm(job, fit, report);
        ok = status == Status::ok || status == Status::not_converged;
        if (ok) sum_m += left_out_error_sum_m(job.result.lm, job.dataset.train().subspan(n - count, count));
      }
      put_pose_back(job.dataset, n, moved, count);  // back: the final fit sees the split's order
    }
    if (ok && (!found || sum_m < best_mae_m)) {
      best_mae_m = sum_m;
      best_t = candidate;
      found = true;
    }
  }
  return best_t;
}

// Not inlined: its fits stay off the stack of the stage that calls it.
[[gnu::noinline]] JointTermHoldout check_on_left_out_poses(Job& job, const LmFit& stage_fit, ParamMask pruned,
                                                           ParamMask new_terms) {
  JointTermHoldout holdout;
  const std::size_t n = job.dataset.train().size();
  if (n > kJointTermHoldoutMaxSamples) return holdout;
  holdout.checked = true;
  static_assert(kJointTermHoldoutMaxSamples <= 256, "move_pose_to_end records positions in a byte");
  std::uint8_t moved[kJointTermHoldoutMaxSamples];
  double error_m[2] = {0.0, 0.0};  // the pose's error: [0] without the added terms, [1] with them
  double with_sum_m = 0.0;
  double without_sum_m = 0.0;
  double improvement_squares_m2 = 0.0;
  bool finished = true;
  for (std::size_t i = 0; finished && i < n; ++i) {
    if (!first_of_its_pose(job.dataset.train(), i)) continue;
    const Sample pose = job.dataset.train()[i];  // a copy: the move reorders the samples
    const std::size_t count = move_pose_to_end(job.dataset, n, pose, moved);
    finished = count < n;  // a single pose cannot be left out
    for (int with_terms = 1; finished && with_terms >= 0; --with_terms) {
      LmFit fit = stage_fit;
      fit.samples = job.dataset.train().subspan(0, n - count);
      fit.significance_t = 0.0;
      fit.fixed_terms |= pruned | (with_terms == 1 ? ParamMask{0} : new_terms);
      ParamMask fold_pruned = 0;
      LmFitReport report;
      report.pruned = &fold_pruned;
      const Status status = fit_lm(job, fit, report);
      finished = status == Status::ok || status == Status::not_converged;
      error_m[with_terms] = left_out_error_sum_m(job.result.lm, job.dataset.train().subspan(n - count, count)) /
                            static_cast<double>(count);
    }
    put_pose_back(job.dataset, n, moved, count);
    if (!finished) break;
    with_sum_m += error_m[1];
    without_sum_m += error_m[0];
    improvement_squares_m2 += (error_m[0] - error_m[1]) * (error_m[0] - error_m[1]);
    ++holdout.poses;
  }
  if (holdout.poses == 0) return holdout;
  const double poses = static_cast<double>(holdout.poses);
  holdout.with_terms_mae_m = with_sum_m / poses;
  holdout.without_terms_mae_m = without_sum_m / poses;
  const double improvement_m = holdout.without_terms_mae_m - holdout.with_terms_mae_m;
  const double variance_m2 =
      holdout.poses > 1 ? std::fmax(0.0, improvement_squares_m2 - poses * improvement_m * improvement_m) / (poses - 1.0)
                        : 0.0;
  holdout.improvement_se_m = std::sqrt(variance_m2 / poses);
  holdout.passed = finished && holdout.poses > 1 && improvement_m > kHoldoutImprovementT * holdout.improvement_se_m;
  return holdout;
}

Status compliance_start(const RobotModel& start, const CalibrationCompliance& options, JointTermFamilySet families,
                        ComplianceModel* out) {
  *out = options.model;
  for (const JointTermFamily& family : kJointTermFamilies) {
    if (options.model.term_count != 0 || family.default_size == 0) continue;
    const Status status = family.append_terms(start, family.default_size, out);
    if (status != Status::ok) return status;
  }
  if ((joint_term_families_of(*out) & ~families) != 0) {  // those terms in their order, the others' slots cleared
    int kept = 0;
    for (int t = 0; t < out->term_count; ++t) {
      const int family = joint_term_family(out->terms[t]);
      if (family < 0 || ((families >> family) & 1) == 0) continue;
      out->terms[kept] = out->terms[t];
      out->coefficient[kept++] = out->coefficient[t];
    }
    for (int t = kept; t < out->term_count; ++t) {
      out->terms[t] = ComplianceTerm{};
      out->coefficient[t] = 0.0;
    }
    out->term_count = kept;
  }
  return check_compliance(*out, start) == Status::ok ? Status::ok : Status::invalid_argument;
}

// Not inlined: its model would stay on the firmware's stack otherwise.
[[gnu::noinline]] JointTermStages joint_term_stages(const RobotModel& start, const CalibrationCompliance& options) {
  ComplianceModel terms;
  const JointTermFamilySet every = all_joint_term_families(kJointTermFamilyCount);
  if (compliance_start(start, options, every, &terms) != Status::ok) {  // refused at the input step
    JointTermStages one;
    one.count = 1;
    one.families[0] = every;
    return one;
  }
  return plan_joint_term_stages(terms);
}

}  // namespace hivecal::detail
