#include "hivecal/solve/lm.hpp"

#include <algorithm>
#include <cmath>
#include <new>

#include "hivecal/solve/cost.hpp"
#include "hivecal/solve/paper6_cost.hpp"
#include "hivecal/core/distributions.hpp"
#include "hivecal/core/math.hpp"
#include "solve/kept_cholesky.hpp"

namespace hivecal {
namespace {

// Median of |r| for an isotropic 3D Gaussian of unit sigma per axis (chi, 3 dof).
constexpr double kMedianNormPerAxisSigma = 1.5381722;
// Automatic Huber threshold: this many per-axis noise sigmas.
constexpr double kHuberNoiseMultiple = 3.0;
// Damping beyond which no step can lower the cost any more at double precision.
constexpr double kMaxDamping = 1e16;
// Joint positions closer than this count as the same pose [rad].
constexpr double kSamePose_rad = 1e-9;
// The prior's variance factor, re-estimated at every accepted point, has converged when it moves
// by less than this share: the prior's pull on a parameter is proportional to it [-].
constexpr double kPriorVarianceTolerance = 1e-3;
// The check of the prior's tolerances against the data (docs/solver-lm.md, "Tolerances checked
// against the data"): the tolerances are widened when the prior's chi-square exceeds its upper
// quantile at this level on the pseudo-observations' redundancy, the level of geodesy's global
// test (a false alarm widens tolerances the data hardly contradict: by little) [-],
constexpr double kPriorToleranceTestLevel = 0.05;
// then re-estimated until the widening changes by less than this share [-],
constexpr double kPriorScaleTolerance = 0.01;
// in at most this many rounds, each a continued fit [-].
constexpr int kMaxPriorRounds = 8;
// Fewer redundant pseudo-observations than this test nothing: the data determine too little [-].
constexpr double kMinPriorRedundancy = 0.5;

bool options_valid(const LmOptions& o, const RobotModel& start) {
  const bool tolerances_ok = o.cost_tolerance >= 0.0 && o.step_tolerance_m >= 0.0 && o.gradient_tolerance >= 0.0;
  const bool damping_ok = o.initial_damping > 0.0 && o.initial_damping < kMaxDamping;
  const bool huber_ok = o.huber_threshold_m >= 0.0 && math::is_finite(o.huber_threshold_m);
  const bool threshold_ok = o.identifiability_threshold > 0.0 && o.identifiability_threshold < 1.0;
  const bool mask_ok =
      o.params != LmParamSet::custom || (o.custom_mask != 0 && (o.custom_mask & ~valid_params_mask(start)) == 0);
  const bool joint_noise_ok = o.joint_sigma_rad >= 0.0 && o.joint_sigma_rad < 1.0 &&
                              (o.joint_sigma_rad == 0.0 || (o.position_sigma_m > 0.0 && o.position_sigma_m < 1.0));
  const LmPriorTolerances& t = o.prior.tolerance;
  const bool prior_ok = t.dh_length_m >= 0.0 && t.dh_angle_rad >= 0.0 && t.tool_m >= 0.0 &&
                        math::is_finite(t.dh_length_m + t.dh_angle_rad + t.tool_m) &&
                        (o.prior.nominal == nullptr || all_finite(to_params(*o.prior.nominal)));
  return o.max_iterations >= 1 && tolerances_ok && damping_ok && huber_ok && threshold_ok && mask_ok &&
         joint_noise_ok && prior_ok;
}

bool poses_distinct(Span<const Sample> samples) {
  for (const Sample& sample : samples) {
    if ((sample.q_rad - samples[0].q_rad).cwiseAbs().maxCoeff() > kSamePose_rad) return true;
  }
  return false;
}

bool transform_finite(const RigidTransform& t) {
  return all_finite(t.rotation) && all_finite(t.translation_m);
}

/// The point the solver is at, with its loss (in the workspace).
using Point = LmPoint;

/// Whether the run estimates the other targets' tool points: with target 1's tool_x, or
/// when asked to (the job's stage estimates the tool point even after fixing tool_x).
bool other_tools_free(const LmOptions& options, ParamMask free_mask, const RobotModel& model) {
  return options.other_target_tools || mask_has(free_mask, tool_param_index(model, 0));
}

/// The Huber threshold to use at `point`: fixed, or from the median residual norm.
Status update_huber_threshold(const LmOptions& options, Span<const Sample> samples, Point* point) {
  if (options.loss != LmLoss::huber) return Status::ok;
  if (options.huber_threshold_m > 0.0) {
    point->loss.huber_threshold_m = options.huber_threshold_m;
    return Status::ok;
  }
  double median_m = 0.0;
  const Status status = median_residual_norm(point->model, point->base, samples, &median_m);
  point->loss.huber_threshold_m = kHuberNoiseMultiple * median_m / kMedianNormPerAxisSigma;
  return status;
}

/// Largest |cos| between a scaled Jacobian column and the weighted residual: `gradient` is
/// J^T W r (with the prior's share), `squares_m2` sum w |r|^2 (with the prior's cost).
double gradient_cosine(const FullParams& gradient, double squares_m2, const FullParams& scale, ParamMask kept) {
  if (!(squares_m2 > 0.0)) return 0.0;
  double largest = 0.0;
  for (int i = 0; i < kFullParamCount; ++i) {
    if (mask_has(kept, i)) largest = std::fmax(largest, std::fabs(gradient(i) * scale(i)));
  }
  return largest / std::sqrt(squares_m2);
}

/// Solves (D H D + damping I) step_s = -D g over the kept parameters, with D H D already in
/// s->system (damped in place) and g in s->gradient; returns the step in parameter units
/// (D step_s), 0 outside `kept`. False when the system cannot be solved.
bool solve_step(LmStepScratch* s, const FullParams& scale, ParamMask kept, double damping, FullParams* step,
                FullParams* scaled_step) {
  FullParams rhs = FullParams::Zero();
  for (int i = 0; i < kFullParamCount; ++i) {
    if (!mask_has(kept, i)) continue;
    s->system(i, i) += damping;
    rhs(i) = -s->gradient(i) * scale(i);
  }
  if (!cholesky_factor(s->system, kept, &s->factorization)) return false;
  cholesky_solve(s->factorization, rhs, scaled_step);
  for (int i = 0; i < kFullParamCount; ++i) {
    if (!mask_has(kept, i)) (*scaled_step)(i) = 0.0;
    (*step)(i) = (*scaled_step)(i)*scale(i);
  }
  return all_finite(*step);
}

/// x^T S x over the kept parameters, S the undamped scaled normal matrix.
double scaled_quadratic(const NormalMatrix& jtwj, const FullParams& scale, ParamMask kept, const FullParams& x) {
  int index[kFullParamCount];
  const int count = mask_indices(kept, index);
  double sum = 0.0;
  for (int jb = 0; jb < count; ++jb) {
    const int b = index[jb];
    for (int ja = 0; ja < count; ++ja) {
      const int a = index[ja];
      sum += x(a) * jtwj(a, b) * scale(a) * scale(b) * x(b);
    }
  }
  return sum;
}

/// Standard deviations of the eliminated tool points: Cov(t_k) = s^2 (D^-1 + A H^-1 A^T) with
/// A = D^-1 S (H the eliminated normal matrix over the kept parameters, factored in `f`).
// Not inlined: its temporaries (several targets only) would sit in calibrate_lm's frame on
// every call (the firmware's stack budget).
[[gnu::noinline]] void other_tool_sigmas(const KeptCholesky& f, const NormalEquations& eq, const FullParams& scale,
                                         ParamMask kept, double variance_m2, LmResult* result) {
  for (int k = 0; k < kMaxTargets - 1; ++k) {
    result->other_tools_sigma_m[k].setZero();
    if (static_cast<std::size_t>(k) >= eq.targets.size()) continue;
    const TargetBlock& block = eq.targets[static_cast<std::size_t>(k)];
    if (block.count == 0) continue;
    const Mat3 inverse = block.tool_tool.inverse();
    const Eigen::Matrix<double, 3, kFullParamCount> a = inverse * block.tool_model;
    for (int axis = 0; axis < 3; ++axis) {
      FullParams scaled_row = FullParams::Zero();
      for (int i = 0; i < kFullParamCount; ++i) scaled_row(i) = mask_has(kept, i) ? a(axis, i) * scale(i) : 0.0;
      FullParams solved;
      cholesky_solve(f, scaled_row, &solved);
      const double variance = inverse(axis, axis) + scaled_row.dot(solved);
      result->other_tools_sigma_m[k](axis) = std::sqrt(std::fmax(variance, 0.0) * variance_m2);
    }
  }
}

/// Checks every input; fills *free_mask.
Status validate_inputs(const RobotModel& start_model, const RigidTransform* start_base, Span<const Sample> samples,
                       const LmOptions& options, ParamMask* free_mask) {
  if (check_joint_layout(start_model) != Status::ok || !options_valid(options, start_model)) {
    return Status::invalid_argument;
  }
  if (samples.empty()) return Status::dataset_empty;
  *free_mask = lm_param_mask(options.params, options.custom_mask, start_model);
  // No floor beyond the base frame: with few samples the identifiability analysis keeps fewer
  // parameters (analyse()); only a set that cannot determine even the base (6) is refused.
  const int determinable = std::min(mask_count(*free_mask), kBaseParamCount);
  if (3 * samples.size() <= static_cast<std::size_t>(determinable)) return Status::too_few_samples;
  if (!all_finite(to_params(start_model))) return Status::non_finite_input;
  const Status compliance = check_compliance(start_model.compliance, start_model);
  if (compliance != Status::ok) return compliance;
  if (start_base != nullptr && !transform_finite(*start_base)) return Status::non_finite_input;
  for (const Sample& sample : samples) {
    if (!all_finite(sample.q_rad) || !all_finite(sample.point_m)) return Status::non_finite_input;
    if (sample.target < 0 || sample.target >= kMaxTargets) return Status::invalid_argument;
  }
  if (!readings_fit_joint_count(samples, start_model.joint_count)) return Status::joint_count_mismatch;
  if (!poses_distinct(samples)) return Status::poses_not_distinct;
  return Status::ok;
}

/// Fills `storage` with the joint trig of every sample and returns the filled part; empty
/// when it cannot hold them all.
Span<const JointTrig> store_joint_trig(const RobotModel& model, Span<const Sample> samples, Span<JointTrig> storage) {
  if (storage.size() < samples.size()) return {};
  for (std::size_t i = 0; i < samples.size(); ++i) storage[i] = joint_trig(model, samples[i].q_rad);
  return Span<const JointTrig>(storage.data(), samples.size());
}

double rms_of(double squares_sum_m2, std::size_t count) {
  return std::sqrt(squares_sum_m2 / static_cast<double>(count));
}

/// Resets *result in place (`*result = LmResult{}` would build a 3.3 kB temporary on the stack).
void clear_result(LmResult* result) {
  result->model = RobotModel{};
  result->base_to_tracker = RigidTransform{};
  clear_report(&result->identifiability);
  result->sigma.setZero();
  for (Vec3& sigma : result->other_tools_sigma_m) sigma.setZero();
  result->loss_sum_m2 = 0.0;
  result->rms_m = 0.0;
  result->residual_sigma_m = 0.0;
  result->huber_threshold_m = 0.0;
  result->iterations = 0;
  result->prior_chi_square = 0.0;
  result->prior_tolerances = LmPriorTolerances{};
  result->termination = LmTermination::max_iterations;
}

/// Everything one calibration works with.
struct Run {
  const RobotModel& start_model;  ///< where the fit started: a parameter found undetermined goes back there
  const LmOptions& options;
  Span<const Sample> samples;
  LmWorkspace* ws;
  LmResult* result;
  ParamMask free_mask;
  ParamMask kept;
  Point& point;                       ///< ws->point
  Span<const JointTrig> sample_trig;  ///< joint trig of every sample, or empty
  NormalEquations* current;           ///< normal equations at `point`
  NormalEquations* trial;             ///< normal equations at the last trial point, in the shared scratch (or null)
  Span<TargetBlock> trial_targets;    ///< the trial's target blocks
  double damping;
  double growth;
  bool reanalysed;  ///< the analysis has been repeated after the first accepted step
  /// The prior's pseudo-observations weigh (p - nominal)^2 / tolerance^2 by this: the fit's
  /// variance factor sum w |r|^2 / dof at the last accepted point (0: no prior) [m^2].
  double prior_variance_m2 = 0.0;
  /// The prior's tolerances: the stated ones, or per kind widened by the variance-component
  /// check (widen_tolerances) [m], [rad].
  LmPriorTolerances tolerances;
  /// The check found the stated tolerances too tight: from then on each kind follows its estimate.
  bool widened = false;
};

/// The prior's weight of parameter i, variance factor / tolerance^2, where it holds one and i
/// is kept; 0 elsewhere [m^2/unit^2].
double prior_weight(const Run& run, int i) {
  if (!mask_has(run.kept, i)) return 0.0;
  const RobotModel* nominal = run.options.prior.nominal;
  const double sigma = nominal != nullptr ? prior_tolerance(run.tolerances, nominal->joint_count, i) : 0.0;
  return sigma > 0.0 ? run.prior_variance_m2 / (sigma * sigma) : 0.0;
}

/// Adds the prior's share of the gradient at `at`, weight (p - nominal), over the kept
/// parameters to *gradient [m^2/unit]. The base and the joint terms hold none.
// Not inlined: its parameter vectors stay out of calibrate_lm's frame (the firmware's stack).
[[gnu::noinline]] void add_prior_gradient(const Run& run, const Point& at, FullParams* gradient) {
  if (!(run.prior_variance_m2 > 0.0)) return;
  const ModelParams p = to_params(at.model);
  const ModelParams nominal = to_params(*run.options.prior.nominal);
  for (int i = 0; i < model_param_count(at.model); ++i) (*gradient)(i) += prior_weight(run, i) * (p(i) - nominal(i));
}

/// The prior's share of the cost at `at`: sum of weight (p - nominal)^2 [m^2].
double prior_cost(const Run& run, const Point& at) {
  if (!(run.prior_variance_m2 > 0.0)) return 0.0;
  const ModelParams p = to_params(at.model);
  const ModelParams nominal = to_params(*run.options.prior.nominal);
  double cost_m2 = 0.0;
  for (int i = 0; i < model_param_count(at.model); ++i)
    cost_m2 += prior_weight(run, i) * (p(i) - nominal(i)) * (p(i) - nominal(i));
  return cost_m2;
}

/// Adds the prior's weights to the diagonal of a system scaled by `scale` over the kept parameters.
void add_prior_diagonal(const Run& run, const FullParams& scale, NormalMatrix* system) {
  for (int i = 0; i < model_param_count(run.point.model); ++i)
    (*system)(i, i) += prior_weight(run, i) * scale(i) * scale(i);
}

/// Residual degrees of freedom of normal equations over `kept`: 3N - p - 3 per eliminated target.
int residual_dof_of(const NormalEquations& eq, ParamMask kept) {
  int eliminated = 0;  // the other targets' tool points, 3 parameters each
  for (const TargetBlock& block : eq.targets) eliminated += block.count > 0 ? 3 : 0;
  return 3 * static_cast<int>(eq.count) - mask_count(kept) - eliminated;
}

/// The prior's variance factor at the current point: the residuals' sum w |r|^2 / dof (at
/// least one degree of freedom), 0 without a prior. Returns whether it moved by more than
/// kPriorVarianceTolerance: the cost the iterations minimise changed with it.
bool update_prior_variance(Run* run) {
  if (run->options.prior.nominal == nullptr) return false;
  const int dof = std::max(1, residual_dof_of(*run->current, run->kept));
  const double before_m2 = run->prior_variance_m2;
  run->prior_variance_m2 = run->current->weighted_squares_m2 / static_cast<double>(dof);
  return !(std::fabs(run->prior_variance_m2 - before_m2) <= kPriorVarianceTolerance * run->prior_variance_m2);
}

/// sigma_p = sqrt(diag((H + P)^-1) * sum w r^2 / (3N - p)) over the kept parameters, from the
/// normal equations at the final point (Jacobi-scaled for conditioning) and the prior's
/// weights P (with a prior: the posterior's sigmas; a parameter the data do not determine
/// keeps about its tolerance).
Status parameter_sigmas(const Run& run, const NormalEquations& eq, ParamMask kept, LmResult* result) {
  const int dof = residual_dof_of(eq, kept);
  result->residual_dof = dof;
  LmStepScratch* s = run.ws->scratch.open_step();
  FullParams scale;
  scale_kept_block(eq.jtwj, kept, &s->system, &scale);
  add_prior_diagonal(run, scale, &s->system);
  if (!cholesky_factor(s->system, kept, &s->factorization)) return Status::singular_system;
  const double variance_m2 = eq.weighted_squares_m2 / static_cast<double>(dof);
  result->residual_sigma_m = std::sqrt(variance_m2);
  FullParams inverse_diagonal;
  cholesky_inverse_diagonal(s->factorization, &s->system, &inverse_diagonal);
  result->sigma.setZero();
  for (int i = 0; i < kFullParamCount; ++i) {
    if (mask_has(kept, i)) result->sigma(i) = std::sqrt(std::fmax(inverse_diagonal(i), 0.0) * variance_m2) * scale(i);
  }
  other_tool_sigmas(s->factorization, eq, scale, kept, variance_m2, result);
  return all_finite(result->sigma) ? Status::ok : Status::singular_system;
}

/// Normal equations of `at` into *out: over the kept parameters, or, while an analysis is
/// ahead, over the free ones plus the base translation (the analysis's reference scale, see
/// analyze_identifiability).
Status accumulate(const Run& run, const Point& at, NormalEquations* out) {
  ParamMask columns = run.kept;
  if (!run.reanalysed) {
    columns = run.free_mask;
    for (int axis = 0; axis < 3; ++axis) columns |= param_bit(base_translation_param_index(at.model, axis));
  }
  // The other targets' tool points are free with target 1's (not in the link-length set).
  if (other_tools_free(run.options, run.free_mask, at.model)) columns |= kOtherTargetTools;
  return accumulate_normal_equations(at.model, at.base, run.samples, at.loss, out, columns, run.sample_trig);
}

/// Identifiability analysis of the current normal equations; sets the kept set and the report.
/// A small set can leave as many identifiable parameters as equations (no residual degree of
/// freedom, no noise estimate, an exact fit of the noise): then the threshold is raised tenfold
/// at a time, so the weakest directions go first, until fewer remain than 3 N, and the report
/// names them; too_few_samples when even that does not get there.
// `inline`: called from start(), move_to() and at the end, it would otherwise get a frame of its own on
// the firmware's deepest stack path (calibrate_lm -> analyze_identifiability -> eigenvectors).
inline Status analyse(Run* run, IdentifiabilityOutput output) {
  const int equations = 3 * static_cast<int>(run->samples.size());
  double threshold = run->options.identifiability_threshold;
  Status status = Status::ok;
  IdentifiabilityWorkspace* scratch = run->ws->scratch.open_identifiability();  // ends the step's and the trial's
  while (true) {
    status = analyze_identifiability(run->current->jtwj, run->free_mask, threshold, scratch,
                                     &run->result->identifiability, harmonic_params_mask(run->point.model), output);
    run->kept = run->result->identifiability.kept_mask;
    if (status != Status::ok || mask_count(run->kept) < equations) return status;
    if (threshold * 10.0 >= 1.0) return Status::too_few_samples;
    threshold *= 10.0;
  }
}

/// Puts the model parameters and joint-term coefficients of `lost` in *model back to their
/// values in `start`; true when one changed. (The base is an increment: it has no start value.)
// Not inlined: its parameter vectors would widen calibrate_lm's frame, on the firmware's deepest path.
[[gnu::noinline]] bool put_back(const RobotModel& start, ParamMask lost, RobotModel* model) {
  if (lost == 0) return false;
  ModelParams params = to_params(*model);
  const ModelParams start_params = to_params(start);
  bool changed = false;
  for (int i = 0; i < model_param_count(*model); ++i) {
    if (!mask_has(lost, i) || params(i) == start_params(i)) continue;
    params(i) = start_params(i);
    changed = true;
  }
  if (changed) set_model_params(params, model);
  for (int t = 0; t < model->compliance.term_count; ++t) {
    double& coefficient = model->compliance.coefficient[t];
    if (!mask_has(lost, compliance_param_index(*model, t)) || coefficient == start.compliance.coefficient[t]) continue;
    coefficient = start.compliance.coefficient[t];
    changed = true;
  }
  return changed;
}

/// Copies the trial point's normal equations into *current, whose target blocks keep their
/// storage: the trial's memory is the analysis's next.
// Not inlined: its copies would widen calibrate_lm's frame, on the firmware's deepest path.
[[gnu::noinline]] void adopt_trial(const NormalEquations& trial, NormalEquations* current) {
  const Span<TargetBlock> blocks = current->targets;
  *current = trial;
  current->targets = blocks;
  for (std::size_t k = 0; k < blocks.size(); ++k) blocks[k] = trial.targets[k];
}

/// Moves to an accepted trial point whose normal equations are in run->trial. Identifiability
/// is a property of the geometry, and a start on a special configuration (a tool point on the
/// flange axis hides theta6 and couples joint 5 with it) has ranks the solution does not: so
/// the analysis made at the start is repeated after the first accepted step, at a generic
/// point, and that one is reported. Sets *kept_changed when it changed the kept set or the
/// prior's variance factor (either changes what the iterations converge to).
Status move_to(Run* run, const Point& trial, bool* kept_changed) {
  run->point = trial;
  adopt_trial(*run->trial, run->current);
  run->trial = nullptr;
  *kept_changed = false;
  const double threshold_before_m = run->point.loss.huber_threshold_m;
  Status status = update_huber_threshold(run->options, run->samples, &run->point);
  if (status == Status::ok && run->point.loss.huber_threshold_m != threshold_before_m) {
    status = accumulate(*run, run->point, run->current);  // IRLS weights for the updated scale
  }
  if (status == Status::ok && !run->reanalysed) {
    const ParamMask before = run->kept;
    run->reanalysed = true;
    status = analyse(run, IdentifiabilityOutput::report);
    *kept_changed = run->kept != before;
    // A parameter the first step moved and this analysis drops is not determined: back to its
    // start value (else it would stay wherever that step put it), and the sums there.
    if (status == Status::ok && put_back(run->start_model, before & ~run->kept, &run->point.model)) {
      status = accumulate(*run, run->point, run->current);
    }
  }
  if (status == Status::ok && update_prior_variance(run)) *kept_changed = true;  // the accepted point's variance
  return status;
}

/// One damped Gauss-Newton step from the current point. Accepts it when the loss drops and
/// adapts the damping (Nielsen). Sets *stop, with the reason, when a convergence test fires
/// or the accepted point cannot be prepared.
bool try_step(Run* run, bool* stop, LmTermination* termination) {
  // The system and its factor are dead once solve_step returns: the trial's normal equations,
  // then move_to's analysis, reuse their memory.
  LmStepScratch* scratch = run->ws->scratch.open_step();
  const LmOptions& options = run->options;
  const NormalEquations& eq = *run->current;
  FullParams& scale = scratch->scale;
  FullParams& step = scratch->step;
  FullParams& scaled_step = scratch->scaled_step;
  scale_kept_block(eq.jtwj, run->kept, &scratch->system, &scale);
  add_prior_diagonal(*run, scale, &scratch->system);
  scratch->gradient = eq.jtwr;
  add_prior_gradient(*run, run->point, &scratch->gradient);
  const double current_loss_m2 = eq.loss_sum_m2 + prior_cost(*run, run->point);
  *stop = true;
  if (gradient_cosine(scratch->gradient, eq.weighted_squares_m2 + prior_cost(*run, run->point), scale, run->kept) <=
      options.gradient_tolerance) {
    *termination = LmTermination::gradient;
    return false;
  }
  if (!solve_step(scratch, scale, run->kept, run->damping, &step, &scaled_step)) {
    *stop = false;
    return false;
  }
  double model_decrease = scaled_quadratic(eq.jtwj, scale, run->kept, scaled_step);
  for (int i = 0; i < model_param_count(run->point.model); ++i)
    model_decrease += prior_weight(*run, i) * step(i) * step(i);
  if (std::sqrt(model_decrease / static_cast<double>(eq.count)) < options.step_tolerance_m) {
    *termination = LmTermination::step_size;
    return false;
  }
  *stop = false;
  // The trial's normal equations are summed right away: steps are nearly always accepted,
  // and then they are the next iteration's (a separate cost pass would be wasted).
  Point& trial = run->ws->trial_point;
  trial = run->point;
  apply_full_increment(step, &trial.model, &trial.base);
  apply_target_step(eq, step, &trial.model);
  // Predicted decrease of sum w|r + J d|^2: d^T S d + 2 lambda |d_s|^2 (scaled units), before
  // the trial's normal equations take the scratch that holds the step.
  const double predicted = model_decrease + 2.0 * run->damping * scaled_step.squaredNorm();
  if (predicted <= options.cost_tolerance * current_loss_m2) {
    // Not even the model promises a change the cost-change test would count: at the optimum up
    // to rounding (a trial there is rejected, its damping raised, again and again, a pass each).
    *stop = true;
    *termination = LmTermination::cost_change;
    return false;
  }
  run->trial = run->ws->scratch.open_trial(run->trial_targets);
  const Status status = accumulate(*run, trial, run->trial);
  const double actual = current_loss_m2 - (run->trial->loss_sum_m2 + prior_cost(*run, trial));
  const double gain = status == Status::ok && predicted > 0.0 ? actual / predicted : -1.0;
  if (!(gain > 0.0)) return false;
  const double cube = 2.0 * gain - 1.0;
  run->damping *= std::fmax(1.0 / 3.0, 1.0 - cube * cube * cube);
  run->growth = 2.0;
  const bool small_change = actual <= options.cost_tolerance * current_loss_m2;
  bool kept_changed = false;
  if (move_to(run, trial, &kept_changed) != Status::ok) {
    *stop = true;  // cannot happen: the same point evaluated finite a moment ago
    *termination = LmTermination::no_progress;
  } else if (small_change && !kept_changed) {
    *stop = true;
    *termination = LmTermination::cost_change;
  }
  return true;
}

/// The Levenberg-Marquardt iterations until a test fires or result->iterations reaches
/// `iteration_limit`. Every iteration that tried a step is traced and reported to the observer.
LmTermination iterate(Run* run, TraceBase* trace, LmObserver* observer, int iteration_limit) {
  LmResult* result = run->result;
  while (result->iterations < iteration_limit) {
    const int iteration = ++result->iterations;
    bool stop = false;
    LmTermination termination = LmTermination::no_progress;
    const double used_damping = run->damping;
    const bool accepted = try_step(run, &stop, &termination);
    if (stop && !accepted) return termination;  // converged before stepping: nothing to report
    if (!accepted) {
      run->damping *= run->growth;
      run->growth *= 2.0;
    }
    const NormalEquations& eq = *run->current;
    const double rms_m = rms_of(eq.squares_sum_m2, eq.count);
    if (trace != nullptr) trace->push(rms_m);
    const LmIterationInfo info{iteration, rms_m, eq.loss_sum_m2, used_damping, accepted};
    if (observer != nullptr && !observer->on_iteration(info)) return LmTermination::cancelled;
    if (stop) return termination;
    if (run->damping > kMaxDamping) return LmTermination::no_progress;
  }
  return LmTermination::max_iterations;
}

/// Starts a run: base transform, Huber scale, normal equations and identifiability at the
/// start point.
Status start(const RigidTransform* start_base_to_tracker, Run* run) {
  Point& point = run->point;
  if (start_base_to_tracker != nullptr) {
    point.base = *start_base_to_tracker;
  } else if (other_tools_free(run->options, run->free_mask, point.model)) {
    // The other targets' tool points are rarely known: least squares for the start geometry.
    const Status fit = fit_base_and_target_tools(run->samples, &point.model, &point.base);
    if (fit != Status::ok) return fit;
  } else {
    const Status fit = fit_base_to_tracker(point.model, run->samples, &point.base);
    if (fit != Status::ok) return fit;
  }
  Status status = update_huber_threshold(run->options, run->samples, &point);
  if (status == Status::ok) status = accumulate(*run, point, run->current);
  if (status != Status::ok) return status;
  // The kept set only: the analysis after the first accepted step reports (complete_report).
  status = analyse(run, IdentifiabilityOutput::kept_set);
  if (status == Status::ok) update_prior_variance(run);
  return status;
}

/// A run that never accepted a step still has the start's analysis, made for its kept set:
/// made again at the same point for the whole report (the same kept set).
Status complete_report(Run* run) {
  if (run->reanalysed) return Status::ok;
  return analyse(run, IdentifiabilityOutput::report);
}

/// The kept set was chosen at the start and after the first accepted step; on a small or
/// degenerate set a direction can still turn null by the final point (the sigmas' factor
/// fails). The analysis is made again there, it names what it drops, and the sigmas are those
/// of what it keeps: the fit itself does not change (a null direction moves no residual).
[[gnu::noinline]] Status reanalyse_at_end(Run* run) {
  run->reanalysed = false;  // the analysis's columns: the free ones and the base translation
  Status status = accumulate(*run, run->point, run->current);
  if (status == Status::ok) status = analyse(run, IdentifiabilityOutput::report);
  run->reanalysed = true;
  if (status != Status::ok) return status;
  return parameter_sigmas(*run, *run->current, run->kept, run->result);
}

Status status_of(LmTermination termination) {
  switch (termination) {
    case LmTermination::max_iterations: return Status::not_converged;
    case LmTermination::cancelled: return Status::solver_cancelled;
    case LmTermination::cost_change:
    case LmTermination::step_size:
    case LmTermination::gradient:
    case LmTermination::no_progress: break;
  }
  return Status::ok;
}

/// The result at the current point: geometry, loss, the prior's chi-square and the sigmas.
Status finish(Run* run) {
  LmResult* result = run->result;
  result->model = run->point.model;
  result->base_to_tracker = run->point.base;
  result->loss_sum_m2 = run->current->loss_sum_m2;
  result->rms_m = rms_of(run->current->squares_sum_m2, run->samples.size());
  result->huber_threshold_m = run->point.loss.huber_threshold_m;
  result->prior_chi_square = run->prior_variance_m2 > 0.0 ? prior_cost(*run, run->point) / run->prior_variance_m2 : 0.0;
  result->prior_tolerances = run->options.prior.nominal != nullptr ? run->tolerances : LmPriorTolerances{};
  Status status = parameter_sigmas(*run, *run->current, run->kept, result);
  if (status == Status::singular_system) status = reanalyse_at_end(run);
  return status;
}

/// The kinds of toleranced parameter, each a group of pseudo-observations with a variance
/// component of its own: DH lengths, DH angles, target 1's tool point.
enum PriorKind { kDhLengths, kDhAngles, kToolPoint, kPriorKinds };

PriorKind prior_kind(int joint_count, int index) {
  if (index >= kParamsPerJoint * joint_count) return kToolPoint;
  return model_param_is_angle(index, joint_count) ? kDhAngles : kDhLengths;
}

double tolerance_of(const LmPriorTolerances& tolerances, PriorKind kind) {
  return kind == kDhLengths ? tolerances.dh_length_m : kind == kDhAngles ? tolerances.dh_angle_rad : tolerances.tool_m;
}

void set_tolerance(LmPriorTolerances* tolerances, PriorKind kind, double value) {
  (kind == kDhLengths  ? tolerances->dh_length_m
   : kind == kDhAngles ? tolerances->dh_angle_rad
                       : tolerances->tool_m) = value;
}

/// The prior's variance components at a converged result (Helmert's estimate, as geodetic
/// adjustment checks groups of observations): over the pseudo-observations of one kind,
/// f = sum_i ((p_i - nominal_i) / tau_i)^2 / sum_i r_i, r_i = 1 - P_ii C_ii the redundancy of
/// pseudo-observation i (its weight P_ii times its posterior variance C_ii = sigma_i^2 / variance
/// factor). With the stated tolerances a chi-square test over every kind on sum r_i degrees of
/// freedom decides (kPriorToleranceTestLevel): the data put the nominal model farther than its
/// tolerances allow, or not (then nothing changes: the same bits). Once widened, each kind's
/// tolerance follows sqrt(f) of its own pseudo-observations (never below the stated one; a kind
/// with too little redundancy keeps its tolerance) until every one settles (kPriorScaleTolerance):
/// lengths and angles are observations of different kinds, and the ratio of their stated
/// tolerances is a guess the data may correct. True when it widened (or re-estimated) them.
// Not inlined: its sums per kind stay out of calibrate_lm's frame, on the firmware's deepest path.
[[gnu::noinline]] bool widen_tolerances(Run* run) {
  const LmResult& result = *run->result;
  if (!(run->prior_variance_m2 > 0.0) || status_of(result.termination) != Status::ok) return false;
  const double variance_m2 = result.residual_sigma_m * result.residual_sigma_m;
  if (!(variance_m2 > 0.0)) return false;
  const RobotModel& nominal = *run->options.prior.nominal;
  const int joint_count = nominal.joint_count;
  double redundancy[kPriorKinds] = {0.0, 0.0, 0.0};
  double chi_square[kPriorKinds] = {0.0, 0.0, 0.0};
  for (int i = 0; i < model_param_count(run->point.model); ++i) {
    const double weight = prior_weight(*run, i);
    if (!(weight > 0.0)) continue;
    const PriorKind kind = prior_kind(joint_count, i);
    redundancy[kind] += 1.0 - weight * result.sigma(i) * result.sigma(i) / variance_m2;
    const double deviation = model_param(run->point.model, i) - model_param(nominal, i);
    chi_square[kind] += weight * deviation * deviation / run->prior_variance_m2;
  }
  if (!run->widened) {
    const double total_redundancy = redundancy[kDhLengths] + redundancy[kDhAngles] + redundancy[kToolPoint];
    const double total = result.prior_chi_square;
    // The upper quantile exceeds the degrees of freedom: a chi-square below them passes untested.
    if (!(total_redundancy >= kMinPriorRedundancy) || total <= total_redundancy ||
        !(total > math::chi_square_upper_quantile(kPriorToleranceTestLevel, total_redundancy))) {
      return false;
    }
    run->widened = true;
  }
  bool moved = false;
  for (int k = 0; k < kPriorKinds; ++k) {
    const PriorKind kind = static_cast<PriorKind>(k);
    if (!(redundancy[kind] >= kMinPriorRedundancy)) continue;
    const double held = tolerance_of(run->tolerances, kind);
    const double widened = std::fmax(tolerance_of(run->options.prior.tolerance, kind),
                                     held * std::sqrt(chi_square[kind] / redundancy[kind]));
    moved = moved || std::fabs(widened - held) > kPriorScaleTolerance * held;
    set_tolerance(&run->tolerances, kind, widened);
  }
  return moved;
}

}  // namespace

// Out of line: one copy of the objects' construction (the reduction's zeroed arrays), not one
// in every caller.
LmStepScratch* LmSharedScratch::open_step() {
  return new (bytes_) LmStepScratch;
}
IdentifiabilityWorkspace* LmSharedScratch::open_identifiability() {
  return new (bytes_) IdentifiabilityWorkspace;
}
NormalEquations* LmSharedScratch::open_trial(Span<TargetBlock> targets) {
  NormalEquations* trial = new (bytes_) NormalEquations;
  trial->targets = targets;
  return trial;
}

const char* lm_termination_name(LmTermination termination) {
  switch (termination) {
    case LmTermination::cost_change: return "cost_change";
    case LmTermination::step_size: return "step_size";
    case LmTermination::gradient: return "gradient";
    case LmTermination::no_progress: return "no_progress";
    case LmTermination::max_iterations: return "max_iterations";
    case LmTermination::cancelled: break;
  }
  return "cancelled";
}

double prior_tolerance(const LmPriorTolerances& tolerance, int joint_count, int index) {
  if (index < 0 || index >= model_param_count(joint_count)) return 0.0;
  return tolerance_of(tolerance, prior_kind(joint_count, index));
}

double lm_prior_sigma(const LmPrior& prior, int index) {
  return prior.nominal == nullptr ? 0.0 : prior_tolerance(prior.tolerance, prior.nominal->joint_count, index);
}

bool tolerances_widened(const LmPriorTolerances& stated, const LmPriorTolerances& held) {
  return held.dh_length_m > stated.dh_length_m || held.dh_angle_rad > stated.dh_angle_rad ||
         held.tool_m > stated.tool_m;
}

LmPrior lm_prior(const RobotModel& nominal, const LmPriorTolerances& tolerance) {
  const bool any = tolerance.dh_length_m > 0.0 || tolerance.dh_angle_rad > 0.0 || tolerance.tool_m > 0.0;
  return any ? LmPrior{&nominal, tolerance} : LmPrior{};
}

ParamMask lm_param_mask(LmParamSet set, ParamMask custom, const RobotModel& start) {
  switch (set) {
    case LmParamSet::full: return rigid_params_mask(start);
    case LmParamSet::full_compliance: return rigid_params_mask(start) | compliance_params_mask(start);
    case LmParamSet::custom: return custom & valid_params_mask(start);
    case LmParamSet::link_lengths: break;
  }
  const LinkLengthSet lengths = link_length_set(start);
  ParamMask mask = 0;
  for (std::size_t k = 0; k < lengths.count; ++k) mask |= param_bit(lengths.param_index[k]);
  for (int i = 0; i < kBaseParamCount; ++i) mask |= param_bit(model_param_count(start) + i);
  return mask;
}

Status calibrate_lm(const RobotModel& start_model, const RigidTransform* start_base_to_tracker,
                    Span<const Sample> samples, const LmOptions& options, LmWorkspace* workspace, LmResult* result,
                    TraceBase* trace, LmObserver* observer) {
  ParamMask free_mask = 0;
  Status status = validate_inputs(start_model, start_base_to_tracker, samples, options, &free_mask);
  if (status != Status::ok) return status;
  const std::size_t blocks = workspace->target_blocks.size() / 2;  // per NormalEquations
  workspace->normal.targets = workspace->target_blocks.subspan(0, blocks);
  if (other_tools_free(options, free_mask, start_model) &&
      static_cast<std::size_t>(target_count(samples) - 1) > blocks) {
    return Status::dimension_out_of_range;  // the workspace has no room for these targets' tool points
  }
  clear_result(result);
  const double joint_noise_ratio =
      options.joint_sigma_rad > 0.0 ? options.joint_sigma_rad / options.position_sigma_m : 0.0;
  workspace->point = Point{start_model, RigidTransform{}, PointLoss{0.0, joint_noise_ratio}};
  Run run{start_model,
          options,
          samples,
          workspace,
          result,
          free_mask,
          0,
          workspace->point,
          store_joint_trig(start_model, samples, workspace->joint_trig),
          &workspace->normal,
          nullptr,
          workspace->target_blocks.subspan(blocks, blocks),
          options.initial_damping,
          2.0,
          false,
          0.0,
          options.prior.tolerance,
          false};
  status = start(start_base_to_tracker, &run);
  if (status != Status::ok) return status;
  if (trace != nullptr) trace->push(rms_of(run.current->squares_sum_m2, samples.size()));
  result->termination = iterate(&run, trace, observer, options.max_iterations);
  status = complete_report(&run);
  if (status == Status::ok) status = finish(&run);
  // The prior's tolerances checked against the data: widened and the fit continued, each round
  // with an iteration budget of its own, while the prior's variance component asks for it.
  for (int round = 0; status == Status::ok && round < kMaxPriorRounds && widen_tolerances(&run); ++round) {
    result->termination = iterate(&run, trace, observer, result->iterations + options.max_iterations);
    status = finish(&run);
  }
  if (status != Status::ok) return status;
  return status_of(result->termination);
}

}  // namespace hivecal
