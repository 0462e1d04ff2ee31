#include "hivecal/calibration.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <new>

#include "hivecal/core/distributions.hpp"
#include "hivecal/core/math.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/model/full_params.hpp"
#include "hivecal/model/rigid_fit.hpp"
#include "hivecal/model/spanning_subset.hpp"
#include "job/blocked_folds.hpp"
#include "job/blunder_search.hpp"
#include "job/term_elimination.hpp"

namespace hivecal {
namespace {

using detail::blocked_fold_errors;
using detail::blunder_limit;
using detail::blunder_test_loss;
using detail::FoldErrors;
using detail::FoldFit;
using detail::harmonics_short_of_their_period;
using detail::index_span;
using detail::job_lm_prior;
using detail::keep_common;
using detail::linearised_term_fixes;
using detail::same_indices;
using detail::screen;
using detail::search_blunders;
using detail::test_blunder_limit;

/// Which stages a method runs.
struct StagePlan {
  bool gsa = false;     ///< GSA on the link lengths
  bool abc = false;     ///< ABC on the link lengths
  bool lm = false;      ///< LM
  bool hybrid = false;  ///< LM starts from the population stage's result
};

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

bool known(const CalibrationOptions& options) {
  return options.method <= CalibrationMethod::all && options.params <= CalibrationParams::paper &&
         (!(options.base_known || options.tool_known) ||
          options.method == CalibrationMethod::lm);  // ABC/GSA fit their own
}

/// The tool point's three bits in the parameters of `model`.
ParamMask tool_params_mask(const RobotModel& model) {
  ParamMask mask = 0;
  for (int axis = 0; axis < 3; ++axis) mask |= param_bit(tool_param_index(model, axis));
  return mask;
}

/// The six base parameters' bits in the parameters of `model`.
ParamMask base_params_mask(const RobotModel& model) {
  ParamMask mask = 0;
  for (int axis = 0; axis < 3; ++axis) {
    mask |= param_bit(base_rotation_param_index(model, axis)) | param_bit(base_translation_param_index(model, axis));
  }
  return mask;
}

/// The base and tool bits the options hold fixed (base_known, tool_known).
ParamMask known_params_mask(const CalibrationOptions& options, const RobotModel& model) {
  return (options.base_known ? base_params_mask(model) : 0) | (options.tool_known ? tool_params_mask(model) : 0);
}

/// The compliance model the LM+compliance stage starts from: the options' terms, or the
/// default ones of `start`'s geometry; `gravity_only`: without the harmonics. invalid_argument
/// when there are none or they are unusable.
Status compliance_start(const RobotModel& start, const CalibrationCompliance& options, bool gravity_only,
                        ComplianceModel* out) {
  *out = options.model;
  if (out->term_count == 0) {
    const Status status = default_compliance_terms(start, options.model.gravity_direction, options.model.load, out);
    if (status != Status::ok) return status;
  }
  if (gravity_only) {  // the gravity terms in their order, the harmonics' slots back to their defaults
    int kept = 0;
    for (int t = 0; t < out->term_count; ++t) {
      if (is_harmonic(out->terms[t])) continue;
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

/// The options' joint terms are gravity terms followed by harmonics (both families, in that
/// order, as the command line builds them): the job then runs LM+compliance (the gravity terms)
/// before LM+compliance+harmonics, so that Table 1 shows what each family bought; the second
/// stage's model extends the first's. Any other mix runs as one stage. Not inlined: its model
/// would stay on the firmware's stack otherwise.
[[gnu::noinline]] bool gravity_stage_first(const RobotModel& start, const CalibrationCompliance& options) {
  ComplianceModel terms;
  if (compliance_start(start, options, false, &terms) != Status::ok) return false;
  int gravity = 0;  // the leading gravity terms
  while (gravity < terms.term_count && !is_harmonic(terms.terms[gravity])) ++gravity;
  for (int t = gravity; t < terms.term_count; ++t)
    if (!is_harmonic(terms.terms[t])) return false;
  return gravity > 0 && gravity < terms.term_count;
}

/// The job's state while it runs: the inputs and where the result goes.
struct Job {
  const RobotModel& start;    ///< the baseline's model: the start joints with the tool point fitted
  const RobotModel& nominal;  ///< the job's start model as given (the tool point given): the prior's centre
  DatasetBase& dataset;
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

/// True when LM dropped a model parameter that `from` holds at another value than `start`:
/// an earlier stage moved a parameter the data cannot determine. Such ones are put back to
/// their start values in *from.
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

/// The value of full-model parameter `index` (geometry or compliance coefficient) in `model`.
double model_value(const RobotModel& model, int index) {
  const int rigid_count = rigid_param_count(model);
  if (index >= rigid_count) return model.compliance.coefficient[index - rigid_count];
  return to_params(model)(index);
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

/// The levels the joint terms of a stage must clear [-].
struct JointTermLevels {
  double gravity_t = 0.0;   ///< a gravity term: CalibrationCompliance::significance_t
  double harmonic_t = 0.0;  ///< a harmonic: that, raised for the whole family (harmonic_level)
  ParamMask harmonics = 0;  ///< the harmonic terms' parameters
};

/// The level a family of `count` harmonic terms must clear with `dof` residual degrees of
/// freedom: `significance_t`, raised so that an arm without any of them keeps one by chance at
/// most kHarmonicFamilyAlpha of the time (Bonferroni: each term two-sided at alpha / count, from
/// Student's t with the fit's dof, as its sigma is estimated from the residuals: 24 harmonics,
/// many samples: 3.53; a fit that leaves no redundancy cannot test a term: infinite) [-].
double harmonic_level(double significance_t, int count, int dof) {
  if (count <= 0) return significance_t;
  if (dof < 1) return std::numeric_limits<double>::infinity();
  const double per_term_tail = kHarmonicFamilyAlpha / static_cast<double>(count);
  const double t_squared = math::f_upper_quantile(per_term_tail, 1.0, static_cast<double>(dof));
  return math::is_finite(t_squared) ? std::fmax(significance_t, std::sqrt(t_squared))
                                    : std::numeric_limits<double>::infinity();
}

/// `compliance_t`: CalibrationCompliance::significance_t; `dof`: the fit's residual degrees of
/// freedom.
JointTermLevels joint_term_levels(const RobotModel& reference, double compliance_t, int dof) {
  JointTermLevels levels;
  levels.gravity_t = compliance_t;
  levels.harmonics = harmonic_params_mask(reference);
  levels.harmonic_t = harmonic_level(compliance_t, mask_count(levels.harmonics), dof);
  return levels;
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
/// >= t, its ratio scaled by t / level to compare); -1 when none is (or t <= 0). The joint terms
/// are tried first, the geometry (when `geometry`) only when every estimated term clears its level: a new term
/// must earn its place, never take a geometry parameter's. (Tried together, a joint's offset,
/// whose sigma a free harmonic sum inflates, would go first, and the sum of sin q, cos 2q and
/// sin 3q, flat over a joint's turn of +-1 rad, would take the offset's place at 20 sigma.)
[[gnu::noinline]] int least_significant(const RobotModel& start, const LmResult& lm, double t,
                                        const JointTermLevels& levels, bool geometry) {
  if (!(t > 0.0)) return -1;
  const ModelParams change = to_params(lm.model) - to_params(start);
  const int model_count = model_param_count(lm.model);
  const int rigid_count = rigid_param_count(lm.model);
  int weakest = -1;
  double weakest_ratio = t;
  const auto consider = [&](int i) {
    if (!mask_has(lm.identifiability.kept_mask, i) || !(lm.sigma(i) > 0.0)) return;
    const double delta = i < model_count ? change(i) : model_value(lm.model, i) - model_value(start, i);
    const double level = mask_has(levels.harmonics, i) ? levels.harmonic_t : levels.gravity_t;
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

/// One LM fit of the job: what it starts from, what it may move, on which samples.
struct LmFit {
  /// The start values (job.start, with the compliance terms and their start coefficients for
  /// the LM+compliance stage): what a dropped or insignificant parameter is put back to.
  const RobotModel* reference = nullptr;
  const RobotModel* start_model = nullptr;  ///< the geometry LM starts from (a stage's or the job's)
  const RigidTransform* base = nullptr;     ///< base -> tracker to start from; null: fitted first
  bool reset_moved = false;                 ///< put back a parameter LM drops that an earlier stage moved
  bool compliance = false;                  ///< the reference's compliance terms are free too, starting on start_model
  Span<const Sample> samples;               ///< the samples fitted
  double significance_t = 0.0;              ///< a change below this many sigma is not significant [-]
  /// Joint terms held at their start values: after LM+compliance, the gravity terms it did not
  /// keep (the harmonics' stage adds harmonics to that model, it does not reopen its choice).
  ParamMask fixed_terms = 0;
  /// Start where the last fit (r.lm) ended instead of start_model: its coefficients kept, those
  /// of fixed_terms put back to their start values; a refit takes a few iterations.
  bool warm = false;
};

/// Joint terms a stage tests from which the test's fixes after the first are made on the
/// linearised fit (term_elimination.hpp): below, a refit per fix is as cheap, and a build that
/// holds fewer terms (the firmware's 4) leaves that code out [-].
constexpr int kLinearisedFixesMinTerms = 5;

/// Whether the test of `reference`'s joint terms makes its fixes on the linearised fit.
constexpr bool linearised_fixes(const RobotModel& reference) {
  return kMaxComplianceTerms >= kLinearisedFixesMinTerms && reference.compliance.term_count >= kLinearisedFixesMinTerms;
}

/// Where a fit reports: its trace, its observer (both may be null), the parameters fixed as
/// not significant.
struct LmFitReport {
  TraceBase* trace = nullptr;      ///< LM's RMS per iteration
  LmObserver* observer = nullptr;  ///< progress
  ParamMask* pruned = nullptr;     ///< receives the parameters fixed as not significant
};

/// LM for `fit` into r.lm. Runs again while (a) it drops a parameter an earlier stage moved
/// (with reset_moved: put back to its start value) or (b) a joint term's coefficient is not
/// plausible (implausible_joint_term, whatever the significance level: fixed at its start value,
/// so that every result reads back) or (c) an estimated parameter's change is not significant
/// (below significance_t sigma: fixed at its start value, one at a time, the least significant
/// first; a small set then fits fewer parameters instead of its noise; the geometry of a larger
/// one is not tested, tests_geometry).
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
  lm.prior = detail::job_lm_prior(o, job.nominal);
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
    const JointTermLevels levels =
        joint_term_levels(reference, job.options.compliance.significance_t, r.lm.residual_dof);
    int weakest = implausible_joint_term(r.lm);
    if (attempt == 0 && !compliance) geometry = tests_geometry(o, fit.samples, r.lm, &r);
    if (weakest < 0) weakest = least_significant(reference, r.lm, fit.significance_t, levels, geometry);
    ParamMask fixes = weakest >= 0 ? param_bit(weakest) : ParamMask{0};
    if (compliance && weakest >= rigid_param_count(reference) && linearised_fixes(reference)) {
      // The terms the test would fix after this one, each after a refit: on the linearised
      // fit at once (the refit below then takes them all).
      const bool other_tools =
          (lm.other_target_tools || mask_has(r.lm.identifiability.kept_mask, tool_param_index(reference, 0)));
      const FoldFit fitted{&r.lm.model, &r.lm.base_to_tracker,
                           r.lm.identifiability.kept_mask | (other_tools ? kOtherTargetTools : ParamMask{0}), lm.prior,
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

/// Candidate significance levels of the automatic choice, from the simplest model down [-].
constexpr double kSignificanceGrid[] = {3.0, 2.0, 1.0, 0.0};

/// The significance level for this stage: options.significance_t, or (when negative and the
/// training set is small) the one of kSignificanceGrid with the least leave-one-out 3-D MAE
/// on the training samples (each pose, with the samples of all its targets, left out and
/// predicted by a fit of the others; ties go to the simpler model); a large set gets
/// kDefaultSignificance.
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

/// Fills the next stage slot from r.lm after an LM stage that ended with `status`.
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

/// LM from the start geometry, or (hybrid) from the previous stage's geometry and base, with
/// the significance test (fit_lm; level from choose_significance).
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

Status run_compliance_lm(Job& job, ParamMask* pruned, bool gravity_only);

/// No new joint term is significant: the data show neither bending nor (after LM+compliance)
/// a harmonic, and the previous fit (the rigid one, or LM+compliance) is the answer (this
/// stage's own pruning of the geometry would differ from it). The previous stage runs again (the
/// same inputs, so the same bits) so that r.lm holds its details; this stage is its copy with
/// the new terms at their start values.
[[gnu::noinline]] Status keep_previous_fit(Job& job, ParamMask* pruned) {
  CalibrationResult& r = job.result;
  const std::size_t index = r.stage_count;
  r.stage_count = index - 1;  // the previous stage refills its own slot and trace
  const CalibrationStage& previous = r.stages[r.stage_count];
  const Status status =
      previous.compliance ? run_compliance_lm(job, pruned, true) : run_lm(job, previous.refines_previous, pruned);
  r.stage_count = index;
  if (status != Status::ok) return status;
  // This slot's model holds the stage's terms at their start values (run_compliance_lm's
  // reference): the previous fit's coefficients go into its terms (a prefix of these), the
  // rest comes from the previous stage.
  CalibrationStage& stage = r.stages[index];
  RobotModel& model = stage.model;
  for (int j = 0; j < kMaxJoints; ++j) model.joints[j] = previous.model.joints[j];
  for (int t = 0; t < kMaxTargets; ++t) target_tool(&model, t) = target_tool(previous.model, t);
  for (int t = 0; t < previous.model.compliance.term_count; ++t) {
    model.compliance.coefficient[t] = previous.model.compliance.coefficient[t];
  }
  stage.solver = previous.solver;
  stage.refines_previous = previous.refines_previous;
  stage.compliance = true;
  stage.rigid_kept = true;
  stage.holdout = JointTermHoldout{};  // run_compliance_lm says when a failed check brought it here
  stage.params = previous.params;
  stage.status = previous.status;
  stage.base_to_tracker = previous.base_to_tracker;
  stage.evaluations = previous.evaluations;
  stage.iterations = previous.iterations;
  stage.best_cost_m = previous.best_cost_m;
  stage.trace_m = previous.trace_m;
  stage.estimated = previous.estimated;
  stage.residual_sigma_m = previous.residual_sigma_m;
  return Status::ok;
}

/// JointTermHoldout for a joint-term stage `stage_fit` that kept some of `new_terms` with the
/// parameters `pruned` fixed: each training pose left out in turn, the others fitted twice with
/// the stage's choice of parameters (no significance test of their own), with and without the
/// `new_terms`. Overwrites r.lm; the dataset's order is restored.
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

/// The fit a joint-term stage adds its terms to (the previous stage's), for the blocked folds.
struct PreviousFit {
  std::size_t stage = 0;    ///< its slot
  ParamMask estimated = 0;  ///< what it estimated
  double sigma_m = 0.0;     ///< its residual sigma per axis [m]
};

/// Two fits' held-out errors summed over some folds: their sums, sums of squares and count.
struct FoldComparison {
  double with_m = 0.0;      ///< sum of the errors with the terms [m]
  double without_m = 0.0;   ///< the same without them [m]
  double with_m2 = 0.0;     ///< sum of the squared errors with the terms [m^2]
  double without_m2 = 0.0;  ///< the same without them [m^2]
  std::size_t count = 0;    ///< samples [-]
  bool unsolved = false;    ///< a fold only the fit without the terms could make
};

/// Adds joint `joint`'s two ends (over the folds `without` could make) to *into and to *all.
void add_ends(const BlockedFoldErrors& with, const BlockedFoldErrors& without, int joint, FoldComparison* into,
              FoldComparison* all) {
  for (int end = 0; end < 2; ++end) {
    if (!without.solved[joint][end]) continue;
    if (!with.solved[joint][end]) {
      into->unsolved = all->unsolved = true;
      continue;
    }
    for (FoldComparison* c : {into, all}) {
      c->with_m += with.sum_m[joint][end];
      c->without_m += without.sum_m[joint][end];
      c->with_m2 += with.squares_m2[joint][end];
      c->without_m2 += without.squares_m2[joint][end];
      c->count += with.count[joint][end];
    }
  }
}

/// The terms predict the folds of `c` worse by more than one standard error of the difference
/// of the two mean errors (each mean's variance from its errors' scatter), or not at all.
bool worse(const FoldComparison& c) {
  if (c.unsolved) return true;
  if (c.count < 2) return false;
  const double n = static_cast<double>(c.count);
  const double with_mean_m = c.with_m / n;
  const double without_mean_m = c.without_m / n;
  const double variance_m2 = (std::fmax(0.0, c.with_m2 / n - with_mean_m * with_mean_m) +
                              std::fmax(0.0, c.without_m2 / n - without_mean_m * without_mean_m)) /
                             (n - 1.0);
  return with_mean_m - without_mean_m > std::sqrt(variance_m2);
}

/// Mean errors with and without the terms over the folds of `c` into *with_m, *without_m [m].
void fold_means(const FoldComparison& c, double* with_m, double* without_m) {
  const double n = c.count > 0 ? static_cast<double>(c.count) : 1.0;
  *with_m = c.count > 0 ? c.with_m / n : 0.0;
  *without_m = c.count > 0 ? c.without_m / n : 0.0;
}

/// The added terms of fit.reference deflecting joint `joint` (0-based).
ParamMask terms_of_joint(const RobotModel& reference, ParamMask terms, int joint) {
  ParamMask mask = 0;
  for (int t = 0; t < reference.compliance.term_count; ++t) {
    if (reference.compliance.terms[t].joint == joint) mask |= param_bit(compliance_param_index(reference, t));
  }
  return mask & terms;
}

/// One check of the blocked folds: r.lm's fit against the previous fit's errors `without`; the
/// comparison into *folds (its rejections kept), and the kept added terms of the joints whose
/// ends they predict worse returned. Not inlined: its fold errors stay off the stack of the
/// refits that follow (the firmware's stack budget).
[[gnu::noinline]] Status compare_folds(Job& job, const LmFit& fit, const BlockedFoldErrors& without,
                                       ParamMask new_terms, BlockedFoldCheck* folds, ParamMask* rejected) {
  const CalibrationResult& r = job.result;
  FoldErrors with{};
  const FoldFit fit_with{&r.lm.model, &r.lm.base_to_tracker, r.lm.identifiability.kept_mask,
                         job_lm_prior(job.options, job.nominal), r.lm.residual_sigma_m * r.lm.residual_sigma_m};
  const Status status =
      blocked_fold_errors(&job.dataset, fit_with, blunder_test_loss(job.options), job.workspace, &with);
  if (status != Status::ok) return status;
  folds->checked = true;
  FoldComparison all;
  *rejected = 0;
  for (int joint = 0; joint < fit.reference->joint_count; ++joint) {
    FoldComparison ends;
    add_ends(with, without, joint, &ends, &all);
    fold_means(ends, &folds->with_terms_mae_m[joint], &folds->without_terms_mae_m[joint]);
    const ParamMask own = terms_of_joint(*fit.reference, r.lm.identifiability.kept_mask & new_terms, joint);
    if (own != 0 && worse(ends)) *rejected |= own;
  }
  fold_means(all, &folds->with_all_mae_m, &folds->without_all_mae_m);
  folds->passed = !worse(all);
  return Status::ok;
}

/// The blocked folds of a joint-term stage (BlockedFoldCheck): r.lm's fit against the previous
/// fit's on each joint's range ends; a joint whose ends its own kept added terms predict worse
/// (or not at all) loses them and the stage is fitted again, up to kMaxFoldRounds checks (a
/// last one that still rejects terms fails the stage); *folds gets the last comparison and
/// whether the kept terms pass over every joint's ends.
[[gnu::noinline]] Status admit_for_the_workspace(Job& job, LmFit* fit, const PreviousFit& previous, ParamMask new_terms,
                                                 const LmFitReport& report, BlockedFoldCheck* folds) {
  constexpr int kMaxFoldRounds = 3;
  CalibrationResult& r = job.result;
  if ((r.lm.identifiability.kept_mask & new_terms) == 0) return Status::ok;
  const CalibrationStage& before = r.stages[previous.stage];
  BlockedFoldErrors& without = job.workspace.previous_fold_errors();
  const FoldFit fit_without{&before.model, &before.base_to_tracker, previous.estimated,
                            job_lm_prior(job.options, job.nominal), previous.sigma_m * previous.sigma_m};
  Status status =
      blocked_fold_errors(&job.dataset, fit_without, blunder_test_loss(job.options), job.workspace, &without);
  for (int round = 0; status == Status::ok && (r.lm.identifiability.kept_mask & new_terms) != 0; ++round) {
    ParamMask rejected = 0;
    status = compare_folds(job, *fit, without, new_terms, folds, &rejected);
    if (status != Status::ok || rejected == 0) break;
    folds->fold_rejected |= rejected;
    if (round + 1 == kMaxFoldRounds) {  // still terms that do not hold beyond their joint's range
      folds->passed = false;
      break;
    }
    fit->fixed_terms |= rejected;
    fit->warm = true;  // fitted again from where this fit ended
    status = fit_lm(job, *fit, report);
    fit->warm = false;
    if (status == Status::not_converged) status = Status::ok;
  }
  return status;
}

/// The last rigid LM stage before slot r.stage_count: what every joint-term stage starts from.
const CalibrationStage& rigid_lm_stage(const CalibrationResult& r) {
  std::size_t k = r.stage_count - 1;
  while (k > 0 && r.stages[k].compliance) --k;
  return r.stages[k];
}

/// LM+compliance: from the rigid LM stage's geometry and base, the geometry and the joint terms
/// (`gravity_only`: the gravity terms alone, before the harmonics' stage) together, at the
/// rigid stage's significance level. A parameter this fit cannot determine goes back to its
/// start value, as in a hybrid. The start model with its terms is built in the new stage's slot
/// (lm_stage fills it after the fit), not on the stack: two models here cost the firmware 1.2 kB
/// above LM's peak.
[[gnu::noinline]] Status run_compliance_lm(Job& job, ParamMask* pruned, bool gravity_only) {
  CalibrationResult& r = job.result;
  const CalibrationStage& rigid = rigid_lm_stage(r);
  const bool after_compliance = r.stages[r.stage_count - 1].compliance;
  RobotModel& reference = r.stages[r.stage_count].model;
  reference = job.start;
  const Status terms = compliance_start(job.start, job.options.compliance, gravity_only, &reference.compliance);
  if (terms != Status::ok) return terms;  // checked at the input step
  TraceBase& trace = job.workspace.trace(r.stage_count);
  LmFit fit;
  fit.reference = &reference;
  fit.start_model = &rigid.model;
  fit.base = &rigid.base_to_tracker;
  fit.reset_moved = true;
  fit.compliance = true;
  fit.samples = job.dataset.train();
  fit.significance_t = r.significance_t;
  if (after_compliance) {  // r.lm is LM+compliance's: its gravity terms (this model's first ones)
    const int gravity_terms = r.stages[r.stage_count - 1].model.compliance.term_count;
    fit.fixed_terms = compliance_params_mask(reference.joint_count, gravity_terms) & ~r.lm.identifiability.kept_mask;
  }
  // The terms this stage adds: every one after the rigid fit, the harmonics after LM+compliance.
  const ParamMask new_terms = after_compliance ? harmonic_params_mask(reference) : compliance_params_mask(reference);
  const std::size_t index = r.stage_count;
  // The previous fit: the blocked folds' reference.
  const PreviousFit previous{index - 1, r.stages[index - 1].estimated, r.stages[index - 1].residual_sigma_m};
  BlockedFoldCheck& folds = r.stages[index].folds;  // in the stage's slot: not on the stack under LM
  folds = BlockedFoldCheck{};
  folds.coverage_rejected = harmonics_short_of_their_period(reference, job.dataset.train()) & new_terms;
  fit.fixed_terms |= folds.coverage_rejected;
  Status status = fit_lm(job, fit, LmFitReport{&trace, job.observer, pruned});
  if (status != Status::ok && status != Status::not_converged) return status;
  status = admit_for_the_workspace(job, &fit, previous, new_terms, LmFitReport{&trace, job.observer, pruned}, &folds);
  if (status != Status::ok && status != Status::not_converged) return status;
  if ((r.lm.identifiability.kept_mask & new_terms) == 0 || !folds.passed) {
    const Status kept = keep_previous_fit(job, pruned);
    return kept;
  }
  const JointTermHoldout holdout = check_on_left_out_poses(job, fit, *pruned, new_terms);
  if (!holdout.checked) {  // a larger set: the significance test and the blocked folds decide
    lm_stage(job, status, true, true, trace);
    return Status::ok;
  }
  Status again = Status::ok;
  if (holdout.passed) {  // the check overwrote r.lm: the same fit again (the same bits)
    again = fit_lm(job, fit, LmFitReport{&trace, nullptr, pruned});
    if (again == Status::ok || again == Status::not_converged) lm_stage(job, again, true, true, trace);
    again = again == Status::not_converged ? Status::ok : again;
  } else {
    again = keep_previous_fit(job, pruned);
  }
  r.stages[index].holdout = holdout;
  return again;
}

/// Tells the observer, if any, that `phase` began or ended.
void report_phase(CalibrationObserver* observer, CalibrationPhase phase, bool ended) {
  if (observer != nullptr) observer->on_phase(phase, ended);
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

/// Baseline and stages on a dataset already split (train / test).
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

/// Resets *result in place (no 5 KB temporary on the stack).
}  // namespace

CalibrationResult::CalibrationResult() = default;

namespace {

CalibrationResult& reset(CalibrationResult* result) {
  result->~CalibrationResult();
  return *new (result) CalibrationResult();
}
}  // namespace

ParamMask calibration_estimated_mask(const CalibrationResult& r) {
  const CalibrationStage& final_stage = r.stages[r.stage_count - 1];
  if (final_stage.solver != CalibrationSolver::lm) return lm_param_mask(LmParamSet::link_lengths, 0, final_stage.model);
  ParamMask mask = r.lm.identifiability.kept_mask;
  for (const Vec3& sigma : r.lm.other_tools_sigma_m) {
    if (sigma.squaredNorm() > 0.0) mask |= kOtherTargetTools;
  }
  return mask;
}

namespace {

/// The compliance options are usable: off, or on with an LM stage and terms.
bool compliance_usable(const RobotModel& start, const CalibrationOptions& options) {
  if (!options.compliance.enabled) return true;
  ComplianceModel model;
  return plan_for(options.method).lm && compliance_start(start, options.compliance, false, &model) == Status::ok;
}

/// Input checks shared by calibrate() and cross_validate().
Status check_inputs(const RobotModel& start, DatasetBase* dataset, const CalibrationOptions& options,
                    CalibrationWorkspaceBase* workspace, CalibrationResult* r) {
  if (dataset == nullptr || workspace == nullptr || !known(options) || check_joint_layout(start) != Status::ok ||
      !compliance_usable(start, options)) {
    return fail(r, CalibrationStep::input, Status::invalid_argument);
  }
  dataset->set_aside(Span<const std::uint32_t>());
  if (dataset->size() == 0) return fail(r, CalibrationStep::input, Status::dataset_empty);
  if (!readings_fit_joint_count(dataset->samples(), start.joint_count)) {
    return fail(r, CalibrationStep::input, Status::joint_count_mismatch);
  }
  return Status::ok;
}

/// One run of the job with `aside` set aside: split, baseline, stages.
Status run_once(const RobotModel& start, DatasetBase* dataset, const CalibrationOptions& options,
                CalibrationWorkspaceBase* workspace, CalibrationResult* result, CalibrationObserver* observer,
                Span<const std::uint32_t> aside) {
  CalibrationResult& r = reset(result);
  dataset->set_aside(aside);
  r.reading_noise = repeated_reading_noise(dataset->samples());  // in the order of add(), before the split reorders
  const Status status = dataset->split(options.train_fraction, options.seed);
  if (status != Status::ok) return fail(&r, CalibrationStep::split, status);
  return run_split(start, dataset, options, workspace, &r, observer);
}

}  // namespace

namespace {

/// Every method and its name: the one table of both directions, in the order of the help.
struct MethodName {
  CalibrationMethod method;
  const char* name;
};
constexpr MethodName kMethodNames[] = {
    {CalibrationMethod::abc_lm, "abc+lm"}, {CalibrationMethod::gsa_lm, "gsa+lm"}, {CalibrationMethod::lm, "lm"},
    {CalibrationMethod::abc, "abc"},       {CalibrationMethod::gsa, "gsa"},       {CalibrationMethod::all, "all"},
};

}  // namespace

const char* calibration_method_name(CalibrationMethod method) {
  for (const MethodName& entry : kMethodNames)
    if (entry.method == method) return entry.name;
  return "unknown";
}

const char* calibration_method_names() {
  return "abc+lm, gsa+lm, lm, abc, gsa, all";
}

Status calibration_method_from_name(const char* name, CalibrationMethod* method) {
  if (name == nullptr || method == nullptr) return Status::invalid_argument;
  for (const MethodName& entry : kMethodNames) {
    if (std::strcmp(entry.name, name) == 0) {
      *method = entry.method;
      return Status::ok;
    }
  }
  return Status::invalid_argument;
}

const char* blunder_verdict_name(BlunderVerdict verdict) {
  switch (verdict) {
    case BlunderVerdict::not_searched: return "not_searched";
    case BlunderVerdict::clean: return "clean";
    case BlunderVerdict::removed: return "removed";
    case BlunderVerdict::model_error: return "model_error";
    case BlunderVerdict::list_full: return "list_full";
    case BlunderVerdict::at_threshold: return "at_threshold";
    case BlunderVerdict::prediction_error: return "prediction_error";
  }
  return "unknown";
}

double parameter_significance_level(const RobotModel& model, int index, double significance_t, double compliance_t,
                                    int dof) {
  if (index < rigid_param_count(model)) return significance_t;
  const JointTermLevels levels = joint_term_levels(model, compliance_t, dof);
  return std::fmax(significance_t, mask_has(levels.harmonics, index) ? levels.harmonic_t : levels.gravity_t);
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
  if (stage.compliance) {
    const ComplianceModel& terms = stage.model.compliance;
    int harmonics = 0;
    for (int t = 0; t < terms.term_count; ++t) harmonics += is_harmonic(terms.terms[t]) ? 1 : 0;
    if (harmonics == 0) return "LM+compliance";
    return harmonics == terms.term_count ? "LM+harmonics" : "LM+compliance+harmonics";
  }
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

namespace {

/// The job with the frames `options` say (fitted, or known): the screen, the runs and the
/// blunder search.
Status run_job(const RobotModel& start, DatasetBase* dataset, const CalibrationOptions& options,
               CalibrationWorkspaceBase* workspace, CalibrationResult* result, CalibrationObserver* observer) {
  Status status = check_inputs(start, dataset, options, workspace, &reset(result));
  if (status != Status::ok) return status;
  if (options.keep_outliers) return run_once(start, dataset, options, workspace, result, observer, {});
  // The two lists live in the workspace (2.6 kB: not on a small target's stack).
  CalibrationOutlierList& aside = workspace->outlier_list(0);
  CalibrationOutlierList& tested = workspace->outlier_list(1);
  report_phase(observer, CalibrationPhase::screen, false);
  status = screen(start, dataset, options, *workspace, &aside);
  report_phase(observer, CalibrationPhase::screen, true);
  if (status != Status::ok) return fail(&reset(result), CalibrationStep::baseline, status);
  // Rerun until the w-test of the calibration sets aside what the run left out: a sample the
  // start geometry's screen flagged comes back when the calibration explains it.
  constexpr std::size_t kMaxRounds = 4;
  BlunderVerdict verdict = BlunderVerdict::not_searched;
  BlunderTestSummary summary;
  std::size_t round = 0;
  bool undecided = false;  // the runs did not agree within kMaxRounds
  while (true) {
    status = run_once(start, dataset, options, workspace, result, observer, index_span(aside));
    if (status != Status::ok) return status;
    ++round;
    report_phase(observer, CalibrationPhase::blunder_test, false);
    verdict = search_blunders(dataset, options, start, *workspace, *result, &tested, &summary);
    report_phase(observer, CalibrationPhase::blunder_test, true);
    if (verdict == BlunderVerdict::not_searched || same_indices(tested, aside) || undecided) break;
    if (round < kMaxRounds) {
      aside = tested;
      continue;
    }
    // No agreement: a pose at the threshold fails the test while fitted and passes when left
    // out (the split moves with it), round after round. What the last two tests did not both
    // flag is kept (a blunder is never made up), and one more run and test are of that set; a
    // pose the final test still flags stays, and the verdict says so.
    undecided = true;
    const std::size_t last_aside = aside.count;
    keep_common(tested, &aside);
    if (aside.count == last_aside) break;  // the last run was of this set already
  }
  // The residuals reported are the final calibration's (of the set the run left out), the w
  // the last test's.
  CalibrationResult& r = *result;
  r.outlier_count = 0;
  const CalibrationStage& final_stage = r.stages[r.stage_count - 1];
  for (const Sample& s : dataset->set_aside()) {
    CalibrationOutlier& o = r.outliers[r.outlier_count++];
    o = CalibrationOutlier{
        s.index, (final_stage.base_to_tracker.apply(fk_sample_point(final_stage.model, s)) - s.point_m).norm()};
    for (const CalibrationOutlier& t : Span<const CalibrationOutlier>(tested.items, tested.count)) {
      if (t.index == s.index) {
        o.w = t.w;
        o.critical_w = t.critical_w;
      }
    }
  }
  r.blunder_verdict = r.outlier_count > 0 && verdict == BlunderVerdict::clean ? BlunderVerdict::removed : verdict;
  if (undecided && verdict == BlunderVerdict::clean && !same_indices(tested, aside)) {
    r.blunder_verdict = BlunderVerdict::at_threshold;
  }
  r.blunder_test = summary;
  r.blunder_limit = blunder_limit(*dataset, options);
  r.test_blunder_limit = test_blunder_limit(*dataset, options);
  r.outlier_rounds = round;
  return Status::ok;
}

/// A fitted base within the gate of the identity (kControllerBaseGate_m, _rad).
bool near_identity(const RigidTransform& base) {
  // |R - I|_F / sqrt(2) is the rotation angle to first order (2 sin(angle / 2) exactly).
  const double angle_rad = (base.rotation - Mat3::Identity()).norm() / std::sqrt(2.0);
  return base.translation_m.norm() <= kControllerBaseGate_m && angle_rad <= kControllerBaseGate_rad;
}

/// The measurement noise per axis the controller's frames must explain the data to: the
/// tracker's scatter over repeated readings when the input has them, else the stated one
/// (CalibrationOptions::measurement_sigma_m, else the blunder test's tracker sigma) [m].
double frames_noise_sigma_m(const CalibrationResult& r, const CalibrationOptions& options) {
  if (r.reading_noise.measured()) return r.reading_noise.sigma_m;
  return options.measurement_sigma_m > 0.0 ? options.measurement_sigma_m : options.blunder_test.tracker_sigma_m;
}

/// The test of the known frames' run (the result's, ended with `known_status`) after the
/// fitted frames' run that set aside `fitted_aside` samples.
ControllerFramesTest test_controller_frames(Status known_status, std::size_t fitted_aside, const CalibrationResult& r,
                                            const CalibrationOptions& options) {
  ControllerFramesTest test;
  test.tested = true;
  test.status = known_status;
  // Known frames that explain the data only with more of it set aside as blunders do not.
  if (test.status == Status::ok && r.outlier_count > fitted_aside) test.status = Status::invalid_argument;
  if (test.status == Status::ok && r.lm.residual_dof < 1) test.status = Status::too_few_samples;
  if (test.status != Status::ok) return test;
  const double dof = static_cast<double>(r.lm.residual_dof);
  test.residual_sigma_m = r.lm.residual_sigma_m;
  test.noise_sigma_m = frames_noise_sigma_m(r, options);
  test.critical_sigma_m =
      test.noise_sigma_m * std::sqrt(math::chi_square_upper_quantile(kControllerFramesAlpha, dof) / dof);
  test.adopted = test.residual_sigma_m <= test.critical_sigma_m;
  return test;
}

/// Whether the job tests the controller's frames (CalibrationOptions::detect_controller_frames).
bool detects_controller_frames(const CalibrationOptions& options) {
  const bool ends_in_lm = plan_for(options.method).lm && options.method != CalibrationMethod::all;  // not a comparison
  return options.detect_controller_frames && !options.base_known && !options.tool_known && ends_in_lm;
}

/// `options` without the test: the frames fitted.
CalibrationOptions fitted_frames(const CalibrationOptions& options) {
  CalibrationOptions fitted = options;
  fitted.detect_controller_frames = false;
  return fitted;
}

/// Sets the controller's frames in *o: the base the identity, the tool points the start
/// model's, LM only (ABC and GSA fit their own base).
void set_controller_frames(CalibrationOptions* o) {
  o->method = CalibrationMethod::lm;
  o->base_known = true;
  o->known_base_to_tracker = RigidTransform{};
  o->tool_known = true;
}

/// The job with the frames test (detects_controller_frames). Not inlined: its copies of the
/// options stay off the stack of a job without it (the firmware's).
[[gnu::noinline]] Status calibrate_detecting_frames(const RobotModel& start, DatasetBase* dataset,
                                                    const CalibrationOptions& options,
                                                    CalibrationWorkspaceBase* workspace, CalibrationResult* result,
                                                    CalibrationObserver* observer) {
  const CalibrationOptions fitted = fitted_frames(options);
  Status status = run_job(start, dataset, fitted, workspace, result, observer);
  const CalibrationStage* final_stage = result->final_stage();
  if (status != Status::ok || !result->has_lm || final_stage == nullptr ||
      !near_identity(final_stage->base_to_tracker)) {
    return status;
  }
  const std::size_t fitted_aside = result->outlier_count;
  CalibrationOptions known = fitted;
  set_controller_frames(&known);
  status = run_job(start, dataset, known, workspace, result, observer);
  const ControllerFramesTest test = test_controller_frames(status, fitted_aside, *result, options);
  if (!test.adopted) status = run_job(start, dataset, fitted, workspace, result, observer);  // the same bits again
  result->frames_test = test;
  return status;
}

}  // namespace

Status calibrate(const RobotModel& start, DatasetBase* dataset, const CalibrationOptions& options,
                 CalibrationWorkspaceBase* workspace, CalibrationResult* result, CalibrationObserver* observer) {
  if (result == nullptr) return Status::invalid_argument;
  if (detects_controller_frames(options)) {
    return calibrate_detecting_frames(start, dataset, options, workspace, result, observer);
  }
  return run_job(start, dataset, options, workspace, result, observer);  // run_job reads no detect flag
}

CalibrationOptions options_with_chosen_frames(const CalibrationOptions& options, const CalibrationResult& result) {
  CalibrationOptions chosen = fitted_frames(options);
  if (result.frames_test.adopted) set_controller_frames(&chosen);
  return chosen;
}

Status test_final_calibration(const CalibrationResult& result, const DatasetBase& dataset,
                              const CalibrationOptions& options, ReliabilityWorkspace* workspace,
                              UnitTestVisitor* visitor, BlunderTestSummary* summary) {
  const CalibrationStage* final_stage = result.final_stage();
  if (final_stage == nullptr || workspace == nullptr || summary == nullptr) return Status::invalid_argument;
  const Span<const Sample> test = dataset.test();
  const Span<const Sample> predicted(test.data(), test.size() + dataset.set_aside().size());  // stored behind it
  return test_for_blunders(final_stage->model, final_stage->base_to_tracker, dataset.train(), predicted,
                           calibration_estimated_mask(result), blunder_test_loss(options), options.blunder_test,
                           workspace, visitor, summary);
}

Status cross_validate(const RobotModel& start, DatasetBase* dataset, const CalibrationOptions& options,
                      std::size_t folds, CalibrationWorkspaceBase* workspace, CalibrationResult* scratch,
                      CrossValidationResult* cv, CalibrationObserver* observer) {
  if (scratch == nullptr || cv == nullptr) return Status::invalid_argument;
  cv->~CrossValidationResult();
  new (cv) CrossValidationResult();
  Status status = Status::ok;
  std::size_t aside_count = 0;
  CalibrationOptions fold_options = fitted_frames(options);
  if (!options.keep_outliers ||
      detects_controller_frames(options)) {  // blunders and frames, found once on the whole set
    status = calibrate(start, dataset, options, workspace, scratch, observer);
    if (status != Status::ok) return cv->status = status;
    aside_count = scratch->outlier_count;  // 0 with keep_outliers
    fold_options = options_with_chosen_frames(options, *scratch);
  } else if (dataset == nullptr || workspace == nullptr || !known(options) || !compliance_usable(start, options)) {
    return cv->status = Status::invalid_argument;
  }
  std::uint32_t aside[kMaxCalibrationOutliers] = {};
  for (std::size_t i = 0; i < aside_count; ++i) aside[i] = scratch->outliers[i].index;
  const Span<const std::uint32_t> aside_span(aside, aside_count);
  dataset->set_aside(aside_span);
  const std::size_t n = dataset->size();
  const std::size_t poses = dataset->pose_count();  // folds hold out whole poses
  const std::size_t k = folds == 0 ? poses : folds;
  if (k < 2 || k > poses || k > kMaxCrossValidationFolds) return cv->status = Status::invalid_argument;
  double abs_sum_m = 0.0;
  double baseline_sum_m = 0.0;
  for (std::size_t f = 0; f < k; ++f) {
    CalibrationResult& r = reset(scratch);
    dataset->set_aside(aside_span);
    status = dataset->split_fold(f, k, options.seed);
    if (status == Status::ok) status = run_split(start, dataset, fold_options, workspace, &r, observer);
    if (status != Status::ok) return cv->status = status;
    CrossValidationFold& fold = cv->folds[f];
    fold.train_count = r.train_count;
    const CalibrationStage& final_stage = r.stages[r.stage_count - 1];  // a method runs one stage at least
    fold.train = final_stage.train;
    fold.test = final_stage.test;
    fold.baseline_test = r.baseline.test;
    const double mae_m = fold.test.mae(ErrorAxis::norm_3d);
    abs_sum_m += mae_m * static_cast<double>(fold.test.count);
    baseline_sum_m += fold.baseline_test.mae(ErrorAxis::norm_3d) * static_cast<double>(fold.baseline_test.count);
    cv->fold_mae_3d_mean_m += mae_m / static_cast<double>(k);
    cv->fold_mae_3d_max_m = std::fmax(cv->fold_mae_3d_max_m, mae_m);
  }
  cv->fold_count = k;
  cv->sample_count = n;
  cv->mae_3d_m = abs_sum_m / static_cast<double>(n);
  cv->baseline_mae_3d_m = baseline_sum_m / static_cast<double>(n);
  cv->status = Status::ok;
  return Status::ok;
}

}  // namespace hivecal
