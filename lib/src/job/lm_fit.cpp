// One LM fit of the job and its significance test (job.hpp): what LM may move, the parameters
// LM dropped or an earlier stage moved put back, the joint terms and (on a small set) the
// geometry fixed one at a time while a change is not significant, and the level chosen on
// left-out poses.
#include <cmath>
#include <limits>

#include "hivecal/core/distributions.hpp"
#include "hivecal/core/math.hpp"
#include "job/blocked_folds.hpp"
#include "job/blunder_search.hpp"
#include "job/job.hpp"
#include "job/term_elimination.hpp"

namespace hivecal::detail {
namespace {

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

}  // namespace

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

JointTermLevels joint_term_levels(const RobotModel& reference, double compliance_t, int dof) {
  JointTermLevels levels;
  levels.gravity_t = compliance_t;
  levels.harmonics = harmonic_params_mask(reference);
  levels.harmonic_t = harmonic_level(compliance_t, mask_count(levels.harmonics), dof);
  return levels;
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

bool first_of_its_pose(Span<const Sample> train, std::size_t i) {
  for (std::size_t j = 0; j < i; ++j) {
    if (same_pose(train[j], train[i])) return false;
  }
  return true;
}

std::size_t move_pose_to_end(DatasetBase& dataset, std::size_t n, const Sample& pose, std::uint8_t* moved) {
  std::size_t count = 0;
  for (std::size_t i = n; i-- > 0;) {  // from the end: a moved sample is never visited again
    if (!same_pose(dataset.samples()[i], pose)) continue;
    dataset.swap_samples(i, n - 1 - count);
    moved[count++] = static_cast<std::uint8_t>(i);
  }
  return count;
}

void put_pose_back(DatasetBase& dataset, std::size_t n, const std::uint8_t* moved, std::size_t count) {
  while (count-- > 0) dataset.swap_samples(moved[count], n - 1 - count);
}

double left_out_error_sum_m(const LmResult& lm, Span<const Sample> samples) {
  double sum_m = 0.0;
  for (const Sample& s : samples) sum_m += (lm.base_to_tracker.apply(fk_sample_point(lm.model, s)) - s.point_m).norm();
  return sum_m;
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

}  // namespace hivecal::detail
