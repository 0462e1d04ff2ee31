// Levenberg-Marquardt calibration of the full model (the geometry parameters + base ->
// tracker transform) from paired samples: streaming normal equations with column scaling,
// automatic identifiability (identifiability.hpp), Nielsen damping, optional Huber loss by
// IRLS, parameter standard deviations. No heap; the large matrices live in LmWorkspace.
// Method and figures: docs/solver-lm.md.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "hivecal/model/dataset.hpp"
#include "hivecal/solve/normal_equations.hpp"
#include "hivecal/solve/identifiability.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/core/status.hpp"
#include "hivecal/core/trace.hpp"
#include "hivecal/core/types.hpp"

namespace hivecal {

/// Which parameters the solver may move (before the identifiability analysis).
enum class LmParamSet : std::uint8_t {
  full,             ///< the rigid model's (33 for six joints); the analysis drops what the data cannot determine
  link_lengths,     ///< the start model's link lengths (link_length_set: for UR the paper's d1, a2, a3, d4, d5, d6) and
                    ///< the base transform
  custom,           ///< LmOptions::custom_mask
  full_compliance,  ///< full and the coefficients of the start model's compliance terms (model/compliance.hpp)
};

/// Loss applied to each sample's residual norm.
enum class LmLoss : std::uint8_t {
  squared,  ///< least squares
  huber,    ///< quadratic up to LmOptions::huber_threshold_m, linear beyond (IRLS weights)
};

/// Why the iterations stopped.
enum class LmTermination : std::uint8_t {
  cost_change,     ///< an accepted step lowered the cost by less than cost_tolerance (relative)
  step_size,       ///< the step moved the predicted points by less than step_tolerance_m (RMS)
  gradient,        ///< every scaled gradient component below gradient_tolerance
  no_progress,     ///< no step lowers the cost any more at machine precision (damping saturated)
  max_iterations,  ///< iteration limit reached (Status::not_converged)
  cancelled,       ///< the observer asked to stop (Status::solver_cancelled)
};

/// Lower-case name of a termination reason ("cost_change", ...).
const char* lm_termination_name(LmTermination termination);

/// Manufacturing tolerances of the nominal model, one standard deviation per element; 0: no
/// prior on that kind (docs/solver-lm.md, "The nominal model as a prior").
struct LmPriorTolerances {
  double dh_length_m = 0.0;   ///< each DH length (d, a) [m]
  double dh_angle_rad = 0.0;  ///< each DH angle (theta offset, alpha) [rad]
  double tool_m = 0.0;        ///< each coordinate of target 1's tool point [m]
};

/// The nominal model as a prior: each toleranced parameter is also observed at its nominal
/// value with its tolerance (a pseudo-observation), weighed against the point residuals by the
/// fit's own variance factor, so that a direction the data do not determine stays at nominal.
/// No prior on the base, the joint terms or the tool points of targets 2.. .
struct LmPrior {
  const RobotModel* nominal = nullptr;  ///< the centre (DH and target 1's tool point); null: no prior
  LmPriorTolerances tolerance;          ///< its tolerances [m], [rad]
};

/// The tolerance of full-model parameter `index` of a model of `joint_count` joints: of its kind
/// for a DH element or target 1's tool point, 0 for every other parameter [m] or [rad].
double prior_tolerance(const LmPriorTolerances& tolerance, int joint_count, int index);
/// The prior's standard deviation of full-model parameter `index`: prior_tolerance, 0 without
/// a nominal [m] or [rad].
double lm_prior_sigma(const LmPrior& prior, int index);
/// Whether `held` (LmResult::prior_tolerances) is wider than `stated` in any kind.
bool tolerances_widened(const LmPriorTolerances& stated, const LmPriorTolerances& held);
/// The prior around `nominal` with `tolerance`; none (a null nominal) when every tolerance is 0.
LmPrior lm_prior(const RobotModel& nominal, const LmPriorTolerances& tolerance);

/// Solver settings; the defaults suit tracker data in metres.
struct LmOptions {
  int max_iterations = 100;         ///< LM iterations, rejected steps included [-]
  double cost_tolerance = 1e-12;    ///< stop on relative cost decrease below this [-]
  double step_tolerance_m = 1e-12;  ///< stop when the step moves predictions less (RMS) [m]
  double gradient_tolerance =
      1e-10;  ///< stop when every scaled column is this close to orthogonal to the residual (|cosine|) [-]
  double initial_damping = 1e-6;   ///< lambda at start, relative to the scaled diagonal (1) [-]
  LmLoss loss = LmLoss::squared;   ///< per-sample loss
  double huber_threshold_m = 0.0;  ///< Huber k [m]; 0: 3 x noise sigma estimated from the median residual
  double identifiability_threshold = kDefaultIdentifiabilityThreshold;  ///< sigma_k / sigma_max to drop [-]
  LmParamSet params = LmParamSet::full;                                 ///< which parameters may move
  /// Free parameters when params == custom (of the start model's valid_params_mask) [-].
  ParamMask custom_mask = rigid_params_mask(kSixJoints);
  /// Estimate the other targets' tool points (targets 2..) even when the free set fixes target
  /// 1's tool_x (e.g. a significance test fixed it); false: only while tool_x is free [-].
  bool other_target_tools = false;
  /// Noise of the joint readings, in the measure position_sigma_m is in (both sigmas, or both
  /// rounding steps: only the ratio counts); > 0 whitens each sample by its point covariance,
  /// I + (joint_sigma_rad / position_sigma_m)^2 J_q J_q^T (errors in variables,
  /// docs/robust.md); 0: off, ordinary least squares, the same bits [rad].
  double joint_sigma_rad = 0.0;
  double position_sigma_m = 1e-5;  ///< stated noise of the measured points, the unit joint_sigma_rad is weighed in [m]
  /// The nominal model as a prior on the free parameters it tolerances (none by default: plain
  /// least squares, the same bits) [-].
  LmPrior prior;
};

/// The free-parameter mask of a parameter set (`custom` for LmParamSet::custom; `start`
/// gives the link lengths and the compliance terms).
ParamMask lm_param_mask(LmParamSet set, ParamMask custom, const RobotModel& start);

/// State after one iteration, for progress display and cancellation.
struct LmIterationInfo {
  int iteration = 0;         ///< 1-based iteration number
  double rms_m = 0.0;        ///< RMS residual norm at the current point [m]
  double loss_sum_m2 = 0.0;  ///< sum of rho(|r_i|) at the current point [m^2]
  double damping = 0.0;      ///< lambda used for the step [-]
  bool accepted = false;     ///< whether the step was taken
};

/// Per-iteration callback (an interface, no std::function).
class LmObserver {
 public:
  /// Called after every iteration; return false to stop (Status::solver_cancelled).
  virtual bool on_iteration(const LmIterationInfo& info) = 0;

 protected:
  LmObserver() = default;
  LmObserver(const LmObserver&) = default;
  LmObserver& operator=(const LmObserver&) = default;
  ~LmObserver() = default;
};

/// Everything the solver returns.
struct LmResult {
  RobotModel model;                       ///< calibrated geometry (dropped parameters at their start values)
  RigidTransform base_to_tracker;         ///< calibrated robot base -> tracker transform
  IdentifiabilityReport identifiability;  ///< what was estimated, what was dropped and why
  FullParams sigma = FullParams::Zero();  ///< standard deviation per parameter [m] or [rad]; 0 when not estimated
  /// Standard deviation of the tool point of targets 2 .. kMaxTargets per axis [m]; 0 when not estimated.
  Vec3 other_tools_sigma_m[kMaxTargets - 1] = {Vec3::Zero(), Vec3::Zero()};
  double loss_sum_m2 = 0.0;        ///< final sum of rho(|r_i|) [m^2] (sum of squares for LmLoss::squared)
  double rms_m = 0.0;              ///< final RMS residual norm, unweighted [m]
  double residual_sigma_m = 0.0;   ///< sqrt(sum w |r|^2 / (3N - p)): noise estimate per axis [m]
  double huber_threshold_m = 0.0;  ///< Huber k used last [m]; 0 for least squares
  int iterations = 0;              ///< iterations run, rejected steps included
  int residual_dof = 0;  ///< 3N - p - the other targets' tool points: residual_sigma_m's degrees of freedom [-]
  /// With a prior: sum over the toleranced parameters of ((p - nominal) / tolerance)^2 at the
  /// result, the pseudo-observations' share of the cost in units of the variance factor [-].
  double prior_chi_square = 0.0;
  /// The tolerances the prior held: the stated ones unless the data put the nominal model
  /// significantly farther off than they allow, then each kind (DH lengths, DH angles, tool)
  /// widened by its own variance component (docs/solver-lm.md "Tolerances checked against the
  /// data"); the fit, its sigmas and prior_chi_square hold these. Zero without a prior [m], [rad].
  LmPriorTolerances prior_tolerances;
  LmTermination termination = LmTermination::max_iterations;  ///< why it stopped
};

/// Cholesky factor of a symmetric positive definite matrix restricted to a parameter set:
/// A(kept, kept) = U^T U, in compact order (position k holds parameter index[k]).
struct KeptCholesky {
  NormalMatrix upper;               ///< U in the leading count x count block (upper triangle) [-]
  int index[kFullParamCount] = {};  ///< parameter at compact position k
  int count = 0;                    ///< parameters factored
};

/// The damped system of one step (or of the final sigmas) and its Cholesky factor.
struct LmStepScratch {
  NormalMatrix system;         ///< scaled, damped system matrix over the kept parameters (the rest unset) [-]
  KeptCholesky factorization;  ///< its Cholesky factor over the kept parameters [-]
  FullParams scale;            ///< column scale of the system [unit/-]
  FullParams step;             ///< the step in parameter units [m] or [rad]
  FullParams scaled_step;      ///< the step in scaled units [-]
  FullParams gradient;         ///< J^T W r and the prior's share, the step's right-hand side [m^2/unit]
};

/// A point of the search: geometry, base and loss. The solver's current and trial points live
/// in its workspace: a RobotModel (with its compliance) is ~0.6 kB, too much for a small stack.
struct LmPoint {
  RobotModel model;     ///< geometry at the point
  RigidTransform base;  ///< base -> tracker transform at the point
  PointLoss loss;       ///< the loss's scale at the point
};

/// One block of memory for three scratch sets that are never alive together: the step's
/// system and factor (each step, the final sigmas), the normal equations at the trial point
/// (from the step until the trial is accepted, copied to the current point, or rejected) and
/// the identifiability analysis (at the start and after the first accepted step: it reads
/// none of the others). Opening one begins a new object in the block and ends the others (all
/// are trivially destructible); a pointer stays valid until another is opened. None reads
/// what was in the block before, so the bits are those of separate storage, 26.6 kB smaller.
class LmSharedScratch {
 public:
  /// Begins the step's scratch (system and factor unset) in the block.
  LmStepScratch* open_step();
  /// Begins the trial point's normal equations (sums unset) over the target blocks `targets`.
  NormalEquations* open_trial(Span<TargetBlock> targets);
  /// Begins the identifiability analysis's scratch in the block.
  IdentifiabilityWorkspace* open_identifiability();

 private:
  static_assert(std::is_trivially_destructible<LmStepScratch>::value &&
                    std::is_trivially_destructible<NormalEquations>::value &&
                    std::is_trivially_destructible<IdentifiabilityWorkspace>::value,
                "opening one scratch set ends the others without a destructor call");
  static constexpr std::size_t kBytes =
      std::max({sizeof(LmStepScratch), sizeof(NormalEquations), sizeof(IdentifiabilityWorkspace)});
  alignas(LmStepScratch) alignas(NormalEquations) alignas(IdentifiabilityWorkspace) unsigned char bytes_[kBytes];
};

/// Scratch memory of the solver (37 kB): give it static storage or put it in the
/// caller's memory plan, not on a small stack.
struct LmWorkspace {
  NormalEquations normal;   ///< normal equations at the current point
  LmPoint point;            ///< the current point
  LmPoint trial_point;      ///< the point a step tries
  LmSharedScratch scratch;  ///< the step's system and factor, the trial point's normal equations, or the
                            ///< identifiability analysis's scratch
  /// Optional storage for the joint trig of the samples, one entry per sample (no ownership):
  /// with it the joint angles' sin/cos are computed once instead of in every pass (~10 %
  /// faster). Too small or empty: computed in every pass. The same bits either way.
  Span<JointTrig> joint_trig;
  /// Storage of the target blocks of the current and the trial normal equations (no
  /// ownership), half each: for samples of several targets, 2 (kMaxTargets - 1) blocks
  /// (~3.6 kB). Empty: one target only (a set of several is refused with
  /// dimension_out_of_range), which small targets choose.
  Span<TargetBlock> target_blocks;
};

/// An LmWorkspace that owns the target blocks: it calibrates sets of up to kMaxTargets targets.
struct LmWorkspaceWithTargets : LmWorkspace {
  LmWorkspaceWithTargets() { target_blocks = Span<TargetBlock>(blocks, kBlockCount); }
  LmWorkspaceWithTargets(const LmWorkspaceWithTargets&) = delete;  // target_blocks views `blocks`
  LmWorkspaceWithTargets& operator=(const LmWorkspaceWithTargets&) = delete;

 private:
  static constexpr std::size_t kBlockCount = 2 * (kMaxTargets - 1);
  TargetBlock blocks[kBlockCount];
};

/// Calibrates `start_model` (and the base transform, from `*start_base_to_tracker` or, when
/// null, from fit_base_to_tracker) on `samples`. Writes every field of *result unless it
/// returns an input error. The optional `trace` receives the RMS residual [m] at the start
/// and after each iteration; `observer` is called after each iteration.
/// Errors: dataset_empty; too_few_samples (3 N <= number of free parameters);
/// non_finite_input (start model, base or samples); invalid_argument (options, a start model
/// that check_joint_layout refuses, or a start compliance that check_compliance refuses);
/// joint_count_mismatch (a sample reads a joint beyond the model's: readings_fit_joint_count);
/// poses_not_distinct (all samples at one joint position); errors of fit_base_to_tracker;
/// singular_system (no identifiable parameter or an unsolvable step);
/// not_converged (iteration limit, *result holds the last point);
/// solver_cancelled (observer, *result holds the last point).
Status calibrate_lm(const RobotModel& start_model, const RigidTransform* start_base_to_tracker,
                    Span<const Sample> samples, const LmOptions& options, LmWorkspace* workspace, LmResult* result,
                    TraceBase* trace = nullptr, LmObserver* observer = nullptr);

}  // namespace hivecal
