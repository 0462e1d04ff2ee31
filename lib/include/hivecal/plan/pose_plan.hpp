// Planning a measurement session before it happens: which joint configurations to measure and
// in which order (docs/planning.md). Candidates are seeded random configurations that meet the
// cell's constraints (joint limits, floor, keep-out cylinder, reflector facing the tracker);
// the selection minimises by default the I-optimality criterion over the cell (the mean
// prediction variance of the tool point anywhere in it), or on request the D-optimality one
// (log det), of the column-scaled information matrix J^T J of the tool-point residuals
// (normal_equations.hpp) plus the geometry's prior precision, over the parameters the pool of
// candidates can identify (identifiability.hpp) with the tool off the flange axis by its prior
// (a real reflector is never on it), by a greedy start and Fedorov exchanges with
// seeded random restarts, then a refinement of each chosen pose in joint space (off the pool,
// within the constraints);
// the chosen poses are ordered for a short movej path (nearest neighbour, then 2-opt).
// No heap: the candidate pool lives in a caller-provided PlanWorkspace.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/core/status.hpp"
#include "hivecal/core/types.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/model/full_params.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/solve/identifiability.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/solve/normal_equations.hpp"

namespace hivecal {

/// Largest candidate pool [-].
inline constexpr std::size_t kPlanCandidateCapacity = 2048;
/// Largest number of planned poses [-].
inline constexpr std::size_t kPlanPoseCapacity = 128;
/// Random draws per requested candidate before the generator gives up [-].
inline constexpr std::size_t kPlanAttemptsPerCandidate = 400;

/// Joint position limits, one entry per joint of the model planned for ([m] for a prismatic
/// joint): the entries beyond its joint count are not read.
struct JointLimits {
  JointVector lower_rad = JointVector::Constant(-2.0 * math::kPi);  ///< lowest joint positions [rad] or [m]
  JointVector upper_rad = JointVector::Constant(2.0 * math::kPi);   ///< highest joint positions [rad] or [m]
};

/// The joint limits of a built-in type: the maker's (maker_joint_limits) for the seven-axis
/// arms; for the UR arms their controllers' (every joint +/-360 deg, the elbow +/-180 deg, as in
/// Universal Robots' ROS description), the same for every UR type.
JointLimits default_joint_limits(RobotType type);

/// Which way the reflector must face.
enum class PlanOrientation : std::uint8_t {
  facing_tracker,  ///< flange z axis within the acceptance angle of the line to the tracker
  tool_down,       ///< flange z axis pointing down (-z of the base), as in the paper's session
};

/// What the selection maximises.
enum class PlanCriterion : std::uint8_t {
  d_optimal,            ///< log det of the scaled information: the smallest confidence volume of the parameters
  i_optimal,            ///< minus the average prediction variance over the candidate pool, tr(M^-1 A)
  i_optimal_workspace,  ///< the same with A over the cell in any orientation: accuracy where the arm works
};

/// Lower-case name of a criterion ("d-optimal", "i-optimal").
const char* plan_criterion_name(PlanCriterion criterion);

/// The cell: where poses may be.
struct PlanConstraints {
  JointLimits limits;                                ///< joint position limits [rad]
  Vec3 tracker_m = Vec3(2.0, 0.0, 0.5);              ///< tracker position in the robot base frame [m]
  double acceptance_rad = 30.0 * math::kPi / 180.0;  ///< largest angle flange z - line to the tracker [rad]
  double floor_z_m = 0.05;                           ///< reflector and flange above this base z [m]
  double keep_out_radius_m = 0.15;  ///< reflector and flange at least this far from the base z axis [m]
  PlanOrientation orientation = PlanOrientation::facing_tracker;  ///< which way the reflector faces
  double tool_down_tolerance_rad = 1e-6;                          ///< tool_down: largest angle flange z - (-z) [rad]
};

/// Settings of one plan.
struct PlanOptions {
  PlanConstraints constraints;                           ///< where poses may be
  std::size_t candidate_count = kPlanCandidateCapacity;  ///< candidates drawn, <= kPlanCandidateCapacity [-]
  std::size_t pose_count = 40;  ///< poses selected, 1 .. kPlanPoseCapacity and <= candidate_count [-]
  std::uint64_t seed = 1;       ///< seed of the candidate draws [-]
  PlanCriterion criterion = PlanCriterion::i_optimal_workspace;  ///< what the selection maximises
  /// Parameters the calibration may move (lm_param_mask of the model planned for) [-].
  ParamMask free_mask = rigid_params_mask(kSixJoints);
  double identifiability_threshold = kDefaultIdentifiabilityThreshold;  ///< as LmOptions [-]
  int max_exchange_passes = 8;    ///< Fedorov exchange passes over the selection [-]
  double prior_length_m = 1e-3;   ///< prior sigma of the geometry's lengths and the tool (0: none) [m]
  double prior_angle_rad = 1e-3;  ///< prior sigma of the geometry's angles (0: none) [rad]
  int restarts = 4;  ///< exchange runs: the greedy start, then seeded random starts; the best criterion wins [-]
  int refine_passes =
      2;  ///< passes moving each selected pose in joint space within the constraints (0: pool poses only) [-]
  double noise_m = 10e-6;                  ///< tracker noise per axis for the predicted sigmas [m]
  double joint_speed_rad_s = 1.05;         ///< movej joint speed (URScript default) [rad/s]
  double joint_acceleration_rad_s2 = 1.4;  ///< movej joint acceleration (URScript default) [rad/s^2]
  double dwell_s = 1.0;                    ///< wait at each pose for the tracker [s]
};

/// Quality of one pose set for the calibration.
struct PoseSetQuality {
  IdentifiabilityReport identifiability;  ///< over options.free_mask: kept, dropped, singular values
  double log_det = 0.0;                   ///< D-criterion over the objective's parameters (PlanResult::objective) [-]
  double prediction_variance =
      0.0;  ///< I-criterion tr(M^-1 A): mean prediction variance over the pool per unit noise variance [-]
  double smallest_singular = 0.0;  ///< smallest singular value of the column-scaled J over the kept parameters [-]
  double condition = 0.0;          ///< condition number over the kept parameters [-]
  FullParams sigma =
      FullParams::Zero();  ///< predicted standard deviation at options.noise_m, 0 if not kept [m] or [rad]
};

/// What a plan produced.
struct PlanResult {
  std::size_t candidate_count = 0;  ///< candidates in the pool [-]
  std::size_t attempts = 0;         ///< random draws made to find them [-]
  IdentifiabilityReport pool;       ///< what the whole pool can identify: no pose set does better
  IdentifiabilityReport objective;  ///< what the pool identifies with the tool off the flange axis by its prior: the
                                    ///< objective's parameters
  std::size_t pose_count = 0;       ///< valid entries of `poses` [-]
  JointVector poses[kPlanPoseCapacity];     ///< the planned poses, in visiting order [rad]
  double greedy_log_det = 0.0;              ///< D-criterion after the greedy start [-]
  double greedy_prediction_variance = 0.0;  ///< I-criterion after the greedy start [-]
  int exchange_passes = 0;                  ///< exchange passes run [-] (of the winning run)
  int exchanges = 0;                        ///< swaps accepted [-] (both of the winning run)
  int best_restart = 0;                     ///< the run that won: 0 the greedy start, k the k-th random start [-]
  PoseSetQuality random;                    ///< the first pose_count candidates (random, same constraints)
  PoseSetQuality planned;                   ///< the planned poses
  double travel_s = 0.0;                    ///< movej time through the poses in order [s]
  double unordered_travel_s = 0.0;          ///< the same in selection order, before ordering [s]
  double session_s = 0.0;                   ///< travel plus one dwell per pose [s]
};

/// Scratch memory of a plan (~280 kB, most of it the candidate pool): give it static storage.
struct PlanWorkspace {
  Sample candidates[kPlanCandidateCapacity];           ///< the pool (points: the nominal tool point)
  Sample selected[kPlanPoseCapacity];                  ///< the current selection
  std::size_t selected_index[kPlanPoseCapacity] = {};  ///< pool index of each selected pose
  Sample best[kPlanPoseCapacity];                      ///< the best selection of the restarts
  bool in_selection[kPlanCandidateCapacity] = {};      ///< pool entries selected
  NormalEquations normal;                              ///< J^T J of a pose set
  NormalMatrix information;                            ///< scaled information of the selection (+ ridge)
  NormalMatrix pool_information;                       ///< A: mean scaled information of one pool candidate
  NormalMatrix scratch;                                ///< scratch of the inverse diagonal
  FullParams ridge = FullParams::Constant(1e-6);  ///< diagonal added to the scaled information (prior precision) [-]
  KeptCholesky factor;                            ///< its Cholesky factor
  IdentifiabilityWorkspace identifiability;       ///< scratch of the identifiability analysis
};

/// True when `q_rad` meets every constraint for `model` (the tool point is the reflector).
bool pose_meets_constraints(const RobotModel& model, const PlanConstraints& constraints, const JointVector& q_rad);

/// Draws options.candidate_count configurations meeting the constraints into
/// workspace->candidates (seeded; tool_down: q5 = -/+ pi/2 alternately and q4 from q2, q3, as
/// a UR's wrist must be for joint 6 to point down). Errors: invalid_argument (options, a
/// model's joint layout, tool_down for an arm of other than six joints), too_few_samples (fewer
/// found in kPlanAttemptsPerCandidate draws each).
Status generate_candidates(const RobotModel& model, const PlanOptions& options, PlanWorkspace* workspace,
                           std::size_t* attempts);

/// Draws the candidate pool (generate_candidates) and analyses what it can identify over
/// options.free_mask: the parameters no pose set under these constraints can identify are
/// the ones it drops; workspace->normal keeps the pool's J^T J. Errors of both steps.
Status pool_identifiability(const RobotModel& model, const PlanOptions& options, PlanWorkspace* workspace,
                            IdentifiabilityReport* report, std::size_t* attempts);

/// Quality of a pose set (J^T J of `model` over options.free_mask, identifiability, sigma at
/// options.noise_m; log_det and prediction_variance of `objective`, the model the selection
/// differentiates, over `objective_mask` with columns multiplied by `scale`, the selection's
/// scale, and workspace->ridge, the prior plan_session set). `poses` must not be workspace
/// storage other than `selected`.
/// Errors of accumulate_normal_equations and analyze_identifiability; singular_system.
Status evaluate_pose_set(const RobotModel& model, const RobotModel& objective, Span<const Sample> poses,
                         const PlanOptions& options, ParamMask objective_mask, const FullParams& scale,
                         PlanWorkspace* workspace, PoseSetQuality* quality);

/// movej time from `from` to `to` [s]: the largest joint move at options' speed and
/// acceleration (trapezoid, or triangle for short moves).
double movej_time_s(const JointVector& from, const JointVector& to, const PlanOptions& options);

/// Orders poses[0 .. count-1] in place for a short open path starting at poses[0]
/// (nearest neighbour, then 2-opt on movej times); returns the path time [s].
double order_poses(JointVector* poses, std::size_t count, const PlanOptions& options);

/// The whole plan: candidates, pool identifiability, greedy + exchange selection (restarts),
/// order, qualities of the plan and of a random set of the same size, durations.
/// Errors: invalid_argument (options: as generate_candidates), too_few_samples, singular_system
/// (nothing identifiable), non_finite_input, errors of analyze_identifiability.
Status plan_session(const RobotModel& model, const PlanOptions& options, PlanWorkspace* workspace, PlanResult* result);

}  // namespace hivecal
