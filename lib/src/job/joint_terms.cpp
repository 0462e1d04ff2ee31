// The joint-term stages (job.hpp, docs/compliance.md): a stage per family of
// kJointTermFamilies in its order (LM+compliance, then LM+compliance+harmonics) after the rigid
// LM, or one of every term; a stage's new terms admitted by the significance test at their
// family's level, their family's coverage rule (the harmonics' period), the blocked folds and,
// on a small set, left-out poses; when none is admitted, the previous fit kept.
#include <cmath>

#include "job/blocked_folds.hpp"
#include "job/blunder_search.hpp"
#include "job/job.hpp"

namespace hivecal::detail {
namespace {

/// No new joint term is admitted: the data show none of the stage's new families (neither
/// bending nor, after LM+compliance, a harmonic), and the previous fit (the rigid one, or the
/// previous joint-term stage's, e.g. LM+compliance) is the answer (this
/// stage's own pruning of the geometry would differ from it). The previous stage runs again (the
/// same inputs, so the same bits) so that r.lm holds its details; this stage is its copy with
/// the new terms at their start values.
[[gnu::noinline]] Status keep_previous_fit(Job& job, ParamMask* pruned) {
  CalibrationResult& r = job.result;
  const std::size_t index = r.stage_count;
  r.stage_count = index - 1;  // the previous stage refills its own slot and trace
  const CalibrationStage& previous = r.stages[r.stage_count];
  const Status status = previous.compliance
                            ? run_compliance_lm(job, pruned, joint_term_families_of(previous.model.compliance))
                            : run_lm(job, previous.refines_previous, pruned);
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
  stage.prior_tolerances = previous.prior_tolerances;
  return Status::ok;
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
                         job_lm_prior(job.nominal, r.lm.prior_tolerances),
                         r.lm.residual_sigma_m * r.lm.residual_sigma_m};
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
                            job_lm_prior(job.nominal, before.prior_tolerances), previous.sigma_m * previous.sigma_m};
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

}  // namespace

[[gnu::noinline]] Status run_compliance_lm(Job& job, ParamMask* pruned, JointTermFamilySet families) {
  CalibrationResult& r = job.result;
  const CalibrationStage& rigid = rigid_lm_stage(r);
  const CalibrationStage& before = r.stages[r.stage_count - 1];
  const bool after_compliance = before.compliance;  // a previous joint-term stage: this one adds families
  RobotModel& reference = r.stages[r.stage_count].model;
  reference = job.start;
  const Status terms = compliance_start(job.start, job.options.compliance, families, &reference.compliance);
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
  // The terms this stage adds: every one after the rigid fit, those of its new families after a
  // joint-term stage (the harmonics after LM+compliance), whose choice it does not reopen: r.lm
  // is that stage's, its terms this model's first ones, those it did not keep held.
  ParamMask new_terms = compliance_params_mask(reference);
  if (after_compliance) {
    const int previous_terms = before.model.compliance.term_count;
    fit.fixed_terms = compliance_params_mask(reference.joint_count, previous_terms) & ~r.lm.identifiability.kept_mask;
    new_terms = joint_term_params_mask(reference, families & ~joint_term_families_of(before.model.compliance));
  }
  const std::size_t index = r.stage_count;
  // The previous fit: the blocked folds' reference.
  const PreviousFit previous{index - 1, r.stages[index - 1].estimated, r.stages[index - 1].residual_sigma_m};
  BlockedFoldCheck& folds = r.stages[index].folds;  // in the stage's slot: not on the stack under LM
  folds = BlockedFoldCheck{};
  folds.coverage_rejected = uncovered_joint_terms(reference, job.dataset.train()) & new_terms;  // the period
  fit.fixed_terms |= folds.coverage_rejected;
  Status status = fit_lm(job, fit, LmFitReport{&trace, job.observer, pruned});
  if (status != Status::ok && status != Status::not_converged) return status;
  status = admit_for_the_workspace(job, &fit, previous, new_terms & blocked_fold_terms(reference),
                                   LmFitReport{&trace, job.observer, pruned}, &folds);
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

}  // namespace hivecal::detail
