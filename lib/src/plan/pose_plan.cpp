#include "hivecal/plan/pose_plan.hpp"

#include <cmath>

#include "hivecal/core/math.hpp"
#include "hivecal/core/random.hpp"
#include "solve/kept_cholesky.hpp"

namespace hivecal {
namespace {

// Ridge added to the scaled information matrix (one average candidate adds ~1 per diagonal
// entry): keeps log det finite while the greedy start holds fewer equations than parameters.
constexpr double kRidge = 1e-6;
// An exchange must improve the criterion by more than this to be taken: no cycling on ties.
constexpr double kExchangeGain = 1e-9;
// Joint-space refinement: first and smallest coordinate step [rad].
constexpr double kRefineStep_rad = 0.2;
constexpr double kRefineMinStep_rad = 0.002;
// 2-opt passes over the path at most (each pass is O(n^2); it usually settles in a few).
constexpr int kMaxTwoOptPasses = 64;
// A 2-opt reversal must save more than this [s].
constexpr double kTwoOptGain_s = 1e-12;

const RigidTransform kIdentity{};

/// A point the flange or the reflector occupies: above the floor, outside the keep-out cylinder.
bool point_allowed(const PlanConstraints& c, const Vec3& p_m) {
  const double radial2 = p_m.x() * p_m.x() + p_m.y() * p_m.y();
  return p_m.z() >= c.floor_z_m && radial2 >= c.keep_out_radius_m * c.keep_out_radius_m;
}

bool within_limits(const JointLimits& limits, const JointVector& q, int joint_count) {
  for (int j = 0; j < joint_count; ++j) {
    if (!(q(j) >= limits.lower_rad(j) && q(j) <= limits.upper_rad(j))) return false;
  }
  return true;
}

bool limits_valid(const JointLimits& limits, int joint_count) {
  if (!all_finite(limits.lower_rad) || !all_finite(limits.upper_rad)) return false;
  for (int j = 0; j < joint_count; ++j) {
    if (!(limits.lower_rad(j) < limits.upper_rad(j))) return false;
  }
  return true;
}

/// Whether the options can plan for `model`: tool_down sets a UR's wrist (point_wrist_down), so
/// it needs a six-joint arm.
bool options_valid(const PlanOptions& o, const RobotModel& model) {
  const PlanConstraints& c = o.constraints;
  const bool orientation_ok = c.orientation != PlanOrientation::tool_down || model.joint_count == kSixJoints;
  const bool cell_ok = limits_valid(c.limits, model.joint_count) && all_finite(c.tracker_m) && c.acceptance_rad > 0.0 &&
                       c.acceptance_rad <= math::kPi && math::is_finite(c.floor_z_m) && c.keep_out_radius_m >= 0.0 &&
                       math::is_finite(c.keep_out_radius_m) && c.tool_down_tolerance_rad > 0.0 &&
                       c.tool_down_tolerance_rad <= math::kPi;
  const bool counts_ok = o.pose_count >= 1 && o.pose_count <= kPlanPoseCapacity && o.candidate_count >= o.pose_count &&
                         o.candidate_count <= kPlanCandidateCapacity;
  const bool mask_ok = o.free_mask != 0 && (o.free_mask & ~valid_params_mask(model)) == 0;
  const bool threshold_ok = o.identifiability_threshold > 0.0 && o.identifiability_threshold < 1.0;
  const bool timing_ok = o.noise_m > 0.0 && math::is_finite(o.noise_m) && o.joint_speed_rad_s > 0.0 &&
                         math::is_finite(o.joint_speed_rad_s) && o.joint_acceleration_rad_s2 > 0.0 &&
                         math::is_finite(o.joint_acceleration_rad_s2) && o.dwell_s >= 0.0 && math::is_finite(o.dwell_s);
  const bool prior_ok = o.prior_length_m >= 0.0 && math::is_finite(o.prior_length_m) && o.prior_angle_rad >= 0.0 &&
                        math::is_finite(o.prior_angle_rad);
  return orientation_ok && cell_ok && counts_ok && mask_ok && threshold_ok && timing_ok && prior_ok &&
         o.max_exchange_passes >= 0 && o.restarts >= 1 && o.refine_passes >= 0 &&
         check_joint_layout(model) == Status::ok;
}

/// Shifts q by whole turns into [lower, upper] when a turn fits (q4 of the tool-down wrist).
double wrap_into(double q, double lower, double upper) {
  const double turn = 2.0 * math::kPi;
  while (q > upper && q - turn >= lower) q -= turn;
  while (q < lower && q + turn <= upper) q += turn;
  return q;
}

/// A UR's joint 6 points down when q5 = -/+ pi/2 and q2 + q3 + q4 = q5 (joints 2-4 parallel):
/// sets q4 from q2, q3, q5.
void point_wrist_down(const PlanConstraints& c, JointVector* q) {
  (*q)(3) = wrap_into((*q)(4) - (*q)(1) - (*q)(2), c.limits.lower_rad(3), c.limits.upper_rad(3));
}

/// One seeded draw: every joint uniform within its limits; tool_down overrides q4 and q5.
JointVector draw_joints(const PlanConstraints& c, int joint_count, std::size_t branch, Random* random) {
  JointVector q;
  for (int j = 0; j < joint_count; ++j) q(j) = random->uniform(c.limits.lower_rad(j), c.limits.upper_rad(j));
  if (c.orientation == PlanOrientation::tool_down) {
    q(4) = branch % 2 == 0 ? -math::kHalfPi : math::kHalfPi;
    point_wrist_down(c, &q);
  }
  return q;
}

/// Jacobian of one pose over the full parameters, columns multiplied by `scale` (0 outside
/// `mask`), from the calibration's own residual Jacobian.
void scaled_jacobian(const RobotModel& model, const Sample& pose, const FullParams& scale, ParamMask mask,
                     FullJacobian* jacobian) {
  (void)local_residual_jacobian(model, kIdentity, pose, jacobian);
  for (int k = 0; k < kFullParamCount; ++k) {
    const double s = mask_has(mask, k) ? scale(k) : 0.0;
    for (int r = 0; r < 3; ++r) (*jacobian)(r, k) *= s;
  }
}

/// *information = ridge I + sum of J^T J over `poses` except entry `skip` (mask x mask block).
void build_information(const RobotModel& model, Span<const Sample> poses, std::size_t skip, const FullParams& scale,
                       ParamMask mask, const FullParams& ridge, NormalMatrix* information) {
  information->setZero();
  for (int k = 0; k < kFullParamCount; ++k) {
    if (mask_has(mask, k)) (*information)(k, k) = ridge(k);
  }
  FullJacobian j;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    if (i == skip) continue;
    scaled_jacobian(model, poses[i], scale, mask, &j);
    for (int b = 0; b < kFullParamCount; ++b) {
      if (!mask_has(mask, b)) continue;
      for (int a = 0; a < kFullParamCount; ++a) {
        if (mask_has(mask, a)) (*information)(a, b) += j(0, a) * j(0, b) + j(1, a) * j(1, b) + j(2, a) * j(2, b);
      }
    }
  }
}

/// log det of the factored matrix: 2 sum log U_kk.
double factor_log_det(const KeptCholesky& f) {
  double sum = 0.0;
  for (int k = 0; k < f.count; ++k) sum += math::log(f.upper(k, k));
  return 2.0 * sum;
}

// The planner scores every candidate of the pool at every exchange step, so these loops are
// its time. Each one carries the three rows of a pose's Jacobian (or the nine products of
// two 3-row sets) side by side: independent sums that the CPU overlaps, where one sum at a
// time waits on each addition. Every sum keeps its own terms in its own order: the bits are
// those of one row at a time.

/// One step of a triangular solve for the three rows: z[r][i] = (z[r][i] - sum over k in
/// [begin, end) of u(k) z[r][k]) / diagonal, where u(k) walks U's column i or row i.
template <typename Entry>
void triangular_step(const Entry& u, int begin, int end, double diagonal, int i, double (*z)[kFullParamCount]) {
  double sum0 = z[0][i], sum1 = z[1][i], sum2 = z[2][i];
  for (int k = begin; k < end; ++k) {
    const double entry = u(k);
    sum0 -= entry * z[0][k];
    sum1 -= entry * z[1][k];
    sum2 -= entry * z[2][k];
  }
  z[0][i] = sum0 / diagonal;
  z[1][i] = sum1 / diagonal;
  z[2][i] = sum2 / diagonal;
}

/// Z = U^-T J^T, column r into z[r] (forward substitution, compact order; M = U^T U).
void forward_solve(const KeptCholesky& f, const FullJacobian& j, double (*z)[kFullParamCount]) {
  for (int i = 0; i < f.count; ++i) {
    for (int r = 0; r < 3; ++r) z[r][i] = j(r, f.index[i]);
    triangular_step([&](int k) { return f.upper(k, i); }, 0, i, f.upper(i, i), i, z);
  }
}

/// Y = U^-1 Z in place (back substitution): Y = M^-1 J^T, compact order.
void back_solve(const KeptCholesky& f, double (*y)[kFullParamCount]) {
  for (int i = f.count - 1; i >= 0; --i) {
    triangular_step([&](int k) { return f.upper(i, k); }, i + 1, f.count, f.upper(i, i), i, y);
  }
}

/// out(r, c) = initial(r, c) + sum over i < count of a[r][i] b[c][i]: the nine sums in one pass.
Mat3 products3(const double (*a)[kFullParamCount], const double (*b)[kFullParamCount], int count, const Mat3& initial) {
  double sum[3][3];
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) sum[r][c] = 0.0;
  }
  for (int i = 0; i < count; ++i) {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) sum[r][c] += a[r][i] * b[c][i];
    }
  }
  Mat3 out;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out(r, c) = initial(r, c) + sum[r][c];
  }
  return out;
}

double det3(const Mat3& g) {
  return g(0, 0) * (g(1, 1) * g(2, 2) - g(1, 2) * g(2, 1)) - g(0, 1) * (g(1, 0) * g(2, 2) - g(1, 2) * g(2, 0)) +
         g(0, 2) * (g(1, 0) * g(2, 1) - g(1, 1) * g(2, 0));
}

/// tr(G^-1 H) of 3x3 matrices by the adjugate (G = I + J M^-1 J^T is positive definite).
double trace_inverse_times(const Mat3& g, const Mat3& h) {
  Mat3 adjugate;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      const int r1 = (c + 1) % 3, r2 = (c + 2) % 3, c1 = (r + 1) % 3, c2 = (r + 2) % 3;
      adjugate(r, c) = g(r1, c1) * g(r2, c2) - g(r1, c2) * g(r2, c1);
    }
  }
  double sum = 0.0;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) sum += adjugate(r, c) * h(c, r);
  }
  return sum / det3(g);
}

/// What adding `pose` to M = U^T U gains: D: log det(I + J M^-1 J^T), the rise of log det M;
/// I: tr((I + J M^-1 J^T)^-1 J M^-1 A M^-1 J^T), the fall of tr(M^-1 A).
double criterion_gain(const RobotModel& model, const Sample& pose, const FullParams& scale, ParamMask mask,
                      const PlanWorkspace& ws, PlanCriterion criterion) {
  const KeptCholesky& f = ws.factor;
  FullJacobian j;
  scaled_jacobian(model, pose, scale, mask, &j);
  double y[3][kFullParamCount];
  forward_solve(f, j, y);
  const Mat3 g = products3(y, y, f.count, Mat3::Identity());
  if (criterion == PlanCriterion::d_optimal) return math::log(det3(g));
  back_solve(f, y);
  double ay[3][kFullParamCount];
  for (int i = 0; i < f.count; i += 2) {  // two rows of A at a time: six sums side by side
    const int row = f.index[i];
    const int next_row = f.index[i + 1 < f.count ? i + 1 : i];
    double sum0 = 0.0, sum1 = 0.0, sum2 = 0.0, next0 = 0.0, next1 = 0.0, next2 = 0.0;
    for (int k = 0; k < f.count; ++k) {
      const int column = f.index[k];
      const double a = ws.pool_information(row, column);
      const double next_a = ws.pool_information(next_row, column);
      sum0 += a * y[0][k];
      sum1 += a * y[1][k];
      sum2 += a * y[2][k];
      next0 += next_a * y[0][k];
      next1 += next_a * y[1][k];
      next2 += next_a * y[2][k];
    }
    ay[0][i] = sum0;
    ay[1][i] = sum1;
    ay[2][i] = sum2;
    if (i + 1 < f.count) {
      ay[0][i + 1] = next0;
      ay[1][i + 1] = next1;
      ay[2][i + 1] = next2;
    }
  }
  const Mat3 h = products3(y, ay, f.count, Mat3::Zero());
  return trace_inverse_times(g, h);
}

/// Factors ridge I + the information of the selection without entry `skip`.
bool factor_selection(const RobotModel& model, PlanWorkspace* ws, std::size_t count, std::size_t skip,
                      const FullParams& scale, ParamMask mask) {
  build_information(model, Span<const Sample>(ws->selected, count), skip, scale, mask, ws->ridge, &ws->information);
  return cholesky_factor(ws->information, mask, &ws->factor);
}

/// The unselected candidate (or `keep`) with the largest gain; `*best_gain` gets the gain.
std::size_t best_candidate(const RobotModel& model, const PlanWorkspace& ws, const PlanOptions& o, std::size_t keep,
                           const FullParams& scale, ParamMask mask, double* best_gain) {
  const std::size_t candidate_count = o.candidate_count;
  std::size_t best = keep;
  double gain_best =
      keep < candidate_count ? criterion_gain(model, ws.candidates[keep], scale, mask, ws, o.criterion) : -1.0;
  for (std::size_t i = 0; i < candidate_count; ++i) {
    if (ws.in_selection[i]) continue;
    const double gain = criterion_gain(model, ws.candidates[i], scale, mask, ws, o.criterion);
    if (gain > gain_best + (keep < candidate_count ? kExchangeGain : 0.0)) {
      gain_best = gain;
      best = i;
    }
  }
  *best_gain = gain_best;
  return best;
}

void select_candidate(PlanWorkspace* ws, std::size_t slot, std::size_t candidate) {
  ws->selected_index[slot] = candidate;
  ws->selected[slot] = ws->candidates[candidate];
  ws->in_selection[candidate] = true;
}

/// Greedy start: adds, pose by pose, the candidate that improves the criterion the most.
Status greedy_start(const RobotModel& model, const PlanOptions& o, const FullParams& scale, ParamMask mask,
                    PlanWorkspace* ws) {
  for (std::size_t i = 0; i < o.candidate_count; ++i) ws->in_selection[i] = false;
  for (std::size_t slot = 0; slot < o.pose_count; ++slot) {
    if (!factor_selection(model, ws, slot, kPlanPoseCapacity, scale, mask)) return Status::singular_system;
    double gain = 0.0;
    const std::size_t best = best_candidate(model, *ws, o, kPlanCandidateCapacity, scale, mask, &gain);
    if (best >= o.candidate_count) return Status::singular_system;
    select_candidate(ws, slot, best);
  }
  return Status::ok;
}

/// Fedorov-style exchange (Cook & Nachtsheim's modified Fedorov): each selected pose in turn
/// is replaced by the candidate that improves the criterion the most, when that beats keeping it.
Status exchange_passes(const RobotModel& model, const PlanOptions& o, const FullParams& scale, ParamMask mask,
                       PlanWorkspace* ws, int* passes, int* exchanges) {
  *passes = 0;
  *exchanges = 0;
  for (int pass = 0; pass < o.max_exchange_passes; ++pass) {
    int swaps = 0;
    for (std::size_t slot = 0; slot < o.pose_count; ++slot) {
      if (!factor_selection(model, ws, o.pose_count, slot, scale, mask)) return Status::singular_system;
      double gain = 0.0;
      const std::size_t current = ws->selected_index[slot];
      const std::size_t best = best_candidate(model, *ws, o, current, scale, mask, &gain);
      if (best == current) continue;
      ws->in_selection[current] = false;
      select_candidate(ws, slot, best);
      ++swaps;
    }
    *passes = pass + 1;
    *exchanges += swaps;
    if (swaps == 0) break;
  }
  return Status::ok;
}

/// Seeded random start: pose_count distinct pool candidates (a restart of the exchange).
void random_start(const PlanOptions& o, std::uint64_t restart, PlanWorkspace* ws) {
  for (std::size_t i = 0; i < o.candidate_count; ++i) ws->in_selection[i] = false;
  Random random(o.seed ^ (0xd1b54a32d192ed03ULL * restart));
  for (std::size_t slot = 0; slot < o.pose_count; ++slot) {
    std::size_t pick = static_cast<std::size_t>(random.below(o.candidate_count));
    while (ws->in_selection[pick]) pick = pick + 1 < o.candidate_count ? pick + 1 : 0;
    select_candidate(ws, slot, pick);
  }
}

/// Moves one pose in joint space while its gain (of `objective`) against the factored rest of
/// the selection rises: coordinate pattern search, steps halving from kRefineStep_rad to
/// kRefineMinStep_rad, every trial within the constraints of `model`, the given tool
/// (tool_down: q4 follows q2, q3 and q5 stays). Returns the pose's final gain.
double refine_pose(const RobotModel& model, const RobotModel& objective, const PlanOptions& o, const FullParams& scale,
                   ParamMask mask, const PlanWorkspace& ws, Sample* pose) {
  const PlanConstraints& c = o.constraints;
  const bool down = c.orientation == PlanOrientation::tool_down;
  double gain = criterion_gain(objective, *pose, scale, mask, ws, o.criterion);
  for (double step = kRefineStep_rad; step >= kRefineMinStep_rad; step *= 0.5) {
    bool improved = true;
    while (improved) {
      improved = false;
      for (int j = 0; j < model.joint_count; ++j) {
        if (down && (j == 3 || j == 4)) continue;
        for (int sign = -1; sign <= 1; sign += 2) {
          Sample trial = *pose;
          trial.q_rad(j) += static_cast<double>(sign) * step;
          if (down) point_wrist_down(c, &trial.q_rad);
          if (!pose_meets_constraints(model, c, trial.q_rad)) continue;
          trial.point_m = fk_tool_point(model, trial.q_rad);
          const double g = criterion_gain(objective, trial, scale, mask, ws, o.criterion);
          if (g > gain + kExchangeGain) {
            gain = g;
            *pose = trial;
            improved = true;
          }
        }
      }
    }
  }
  return gain;
}

/// Continuous refinement beyond the finite pool: options.refine_passes passes of refine_pose
/// over the selection, each pose against the rest as they stand.
Status refine_selection(const RobotModel& model, const RobotModel& objective, const PlanOptions& o,
                        const FullParams& scale, ParamMask mask, PlanWorkspace* ws) {
  for (int pass = 0; pass < o.refine_passes; ++pass) {
    for (std::size_t slot = 0; slot < o.pose_count; ++slot) {
      if (!factor_selection(objective, ws, o.pose_count, slot, scale, mask)) return Status::singular_system;
      Sample pose = ws->selected[slot];
      (void)refine_pose(model, objective, o, scale, mask, *ws, &pose);
      ws->selected[slot] = pose;
    }
  }
  return Status::ok;
}

/// D- and I-criteria of a pose set over `mask` with the pool's scale (ridge included).
bool pose_set_criteria(const RobotModel& model, Span<const Sample> poses, const FullParams& scale, ParamMask mask,
                       PlanWorkspace* ws, double* log_det, double* prediction_variance) {
  build_information(model, poses, kPlanPoseCapacity, scale, mask, ws->ridge, &ws->information);
  if (!cholesky_factor(ws->information, mask, &ws->factor)) return false;
  *log_det = factor_log_det(ws->factor);
  double trace = 0.0;  // tr(M^-1 A) = sum_k (M^-1 a_k)_k
  FullParams column;
  FullParams solved;
  for (int k = 0; k < kFullParamCount; ++k) {
    if (!mask_has(mask, k)) continue;
    column = ws->pool_information.col(k);
    cholesky_solve(ws->factor, column, &solved);
    trace += solved(k);
  }
  *prediction_variance = trace;
  return true;
}

/// The criterion a plan minimises: -log det (D) or tr(M^-1 A) (I) of the current selection.
bool selection_cost(const RobotModel& model, const PlanOptions& o, const FullParams& scale, ParamMask mask,
                    PlanWorkspace* ws, double* cost) {
  double log_det = 0.0;
  double variance = 0.0;
  if (!pose_set_criteria(model, Span<const Sample>(ws->selected, o.pose_count), scale, mask, ws, &log_det, &variance)) {
    return false;
  }
  *cost = o.criterion == PlanCriterion::d_optimal ? -log_det : variance;
  return true;
}

/// Greedy start and exchanges, then options.restarts - 1 seeded random starts with their own
/// exchanges; the selection with the best criterion (the first on ties), refined, is left in
/// ws. `model` is the objective's, `constraint_model` the one the constraints hold for.
Status select_poses(const RobotModel& constraint_model, const RobotModel& model, const PlanOptions& o,
                    const FullParams& scale, ParamMask mask, PlanWorkspace* ws, PlanResult* result) {
  Status status = greedy_start(model, o, scale, mask, ws);
  if (status != Status::ok) return status;
  if (!pose_set_criteria(model, Span<const Sample>(ws->selected, o.pose_count), scale, mask, ws,
                         &result->greedy_log_det, &result->greedy_prediction_variance)) {
    return Status::singular_system;
  }
  double best_cost = 0.0;
  for (int restart = 0; restart < o.restarts; ++restart) {
    if (restart > 0) random_start(o, static_cast<std::uint64_t>(restart), ws);
    int passes = 0;
    int exchanges = 0;
    status = exchange_passes(model, o, scale, mask, ws, &passes, &exchanges);
    if (status != Status::ok) return status;
    double cost = 0.0;
    if (!selection_cost(model, o, scale, mask, ws, &cost)) return Status::singular_system;
    if (restart == 0 || cost < best_cost) {
      best_cost = cost;
      result->best_restart = restart;
      result->exchange_passes = passes;
      result->exchanges = exchanges;
      for (std::size_t i = 0; i < o.pose_count; ++i) ws->best[i] = ws->selected[i];
    }
  }
  for (std::size_t i = 0; i < o.pose_count; ++i) ws->selected[i] = ws->best[i];
  return refine_selection(constraint_model, model, o, scale, mask, ws);
}

/// The model the objective differentiates: the tool displaced across the flange axis by its
/// prior sigma in x and in y (the RMS radius of a tool known to that sigma per axis). A real
/// reflector is never exactly on the axis, and what an off-axis one makes identifiable (theta5,
/// d5: the calibration estimates them) belongs in the objective. The constraints and the
/// reported identifiability and sigmas keep the given tool.
RobotModel objective_model(const RobotModel& model, const PlanOptions& o) {
  RobotModel objective = model;
  objective.tool_m += Vec3(o.prior_length_m, o.prior_length_m, 0.0);
  return objective;
}

/// Pool scale: 1 / RMS column norm per candidate, so one average candidate adds 1 per
/// diagonal entry (D-optimality does not depend on it; the ridge and the numbers do).
FullParams pool_scale(const NormalMatrix& jtj, std::size_t count, ParamMask mask) {
  FullParams scale = FullParams::Ones();
  for (int k = 0; k < kFullParamCount; ++k) {
    if (mask_has(mask, k) && jtj(k, k) > 0.0) scale(k) = std::sqrt(static_cast<double>(count) / jtj(k, k));
  }
  return scale;
}

/// The diagonal added to the scaled information: the prior precision of each geometry parameter
/// of `model` (noise / prior sigma)^2 in the selection's scale, at least kRidge; the base has no
/// prior.
FullParams prior_ridge(const RobotModel& model, const NormalMatrix& jtj, const FullParams& scale,
                       const PlanOptions& o) {
  FullParams ridge = FullParams::Constant(kRidge);
  for (int k = 0; k < model_param_count(model); ++k) {
    const bool is_angle = model_param_is_angle(k, model.joint_count);
    const double prior = is_angle ? o.prior_angle_rad : o.prior_length_m;
    if (prior > 0.0 && jtj(k, k) > 0.0) {
      const double precision = (o.noise_m / prior) * (o.noise_m / prior);  // in units of the noise's
      ridge(k) = std::fmax(kRidge, precision * scale(k) * scale(k));
    }
  }
  return ridge;
}

/// A = S (J^T J) S / count over mask x mask, 0 elsewhere: one average candidate's information.
void mean_scaled_information(const NormalMatrix& jtj, std::size_t count, const FullParams& scale, ParamMask mask,
                             NormalMatrix* mean) {
  for (int b = 0; b < kFullParamCount; ++b) {  // element by element: jtj may be *mean
    for (int a = 0; a < kFullParamCount; ++a) {
      const bool inside = mask_has(mask, a) && mask_has(mask, b);
      (*mean)(a, b) = inside ? scale(a) * jtj(a, b) * scale(b) / static_cast<double>(count) : 0.0;
    }
  }
}

double path_time_s(const JointVector* poses, std::size_t count, const PlanOptions& o) {
  double sum = 0.0;
  for (std::size_t i = 1; i < count; ++i) sum += movej_time_s(poses[i - 1], poses[i], o);
  return sum;
}

void nearest_neighbour(JointVector* poses, std::size_t count, const PlanOptions& o) {
  for (std::size_t i = 1; i < count; ++i) {
    std::size_t best = i;
    double best_s = movej_time_s(poses[i - 1], poses[i], o);
    for (std::size_t k = i + 1; k < count; ++k) {
      const double t = movej_time_s(poses[i - 1], poses[k], o);
      if (t < best_s) {
        best_s = t;
        best = k;
      }
    }
    const JointVector swap = poses[i];
    poses[i] = poses[best];
    poses[best] = swap;
  }
}

void reverse_segment(JointVector* poses, std::size_t first, std::size_t last) {
  while (first < last) {
    const JointVector swap = poses[first];
    poses[first] = poses[last];
    poses[last] = swap;
    ++first;
    --last;
  }
}

/// 2-opt on an open path with a fixed start: reverses poses[i..k] when that shortens it.
void two_opt(JointVector* poses, std::size_t count, const PlanOptions& o) {
  for (int pass = 0; pass < kMaxTwoOptPasses; ++pass) {
    bool improved = false;
    for (std::size_t i = 1; i + 1 < count; ++i) {
      for (std::size_t k = i + 1; k < count; ++k) {
        const bool has_next = k + 1 < count;
        const double before =
            movej_time_s(poses[i - 1], poses[i], o) + (has_next ? movej_time_s(poses[k], poses[k + 1], o) : 0.0);
        const double after =
            movej_time_s(poses[i - 1], poses[k], o) + (has_next ? movej_time_s(poses[i], poses[k + 1], o) : 0.0);
        if (after < before - kTwoOptGain_s) {
          reverse_segment(poses, i, k);
          improved = true;
        }
      }
    }
    if (!improved) return;
  }
}

}  // namespace

const char* plan_criterion_name(PlanCriterion criterion) {
  switch (criterion) {
    case PlanCriterion::i_optimal: return "i-optimal";
    case PlanCriterion::i_optimal_workspace: return "i-optimal-workspace";
    case PlanCriterion::d_optimal: break;
  }
  return "d-optimal";
}

JointLimits default_joint_limits(RobotType type) {
  JointLimits limits;
  if (maker_joint_limits(type, &limits.lower_rad, &limits.upper_rad) == Status::ok) return limits;
  // every built-in UR type has the same controller limits
  limits.lower_rad(2) = -math::kPi;
  limits.upper_rad(2) = math::kPi;
  return limits;
}

bool pose_meets_constraints(const RobotModel& model, const PlanConstraints& c, const JointVector& q_rad) {
  if (!within_limits(c.limits, q_rad, model.joint_count)) return false;
  const RigidTransform flange = fk_flange(model, q_rad);
  const Vec3 reflector = flange.apply(model.tool_m);
  if (!point_allowed(c, reflector) || !point_allowed(c, flange.translation_m)) return false;
  const Vec3 axis = flange.rotation.col(2);
  // Both cosines are math::cos, the library's own (core/math.hpp), not libm's: the same bits on
  // every target, as the plan's golden digest checks.
  if (c.orientation == PlanOrientation::tool_down) {
    const double cos_tolerance = math::cos(c.tool_down_tolerance_rad);  // own cos (core/math.hpp), not libm
    return -axis.z() >= cos_tolerance;
  }
  const Vec3 to_tracker = c.tracker_m - reflector;
  const double distance_m = to_tracker.norm();
  const double cos_acceptance = math::cos(c.acceptance_rad);  // own cos (core/math.hpp), not libm
  return distance_m > 0.0 && axis.dot(to_tracker) >= cos_acceptance * distance_m;
}

Status generate_candidates(const RobotModel& model, const PlanOptions& options, PlanWorkspace* workspace,
                           std::size_t* attempts) {
  if (!options_valid(options, model)) return Status::invalid_argument;
  Random random(options.seed);
  const std::size_t limit = kPlanAttemptsPerCandidate * options.candidate_count;
  std::size_t found = 0;
  std::size_t draws = 0;
  while (found < options.candidate_count && draws < limit) {
    const JointVector q = draw_joints(options.constraints, model.joint_count, draws, &random);
    ++draws;
    if (!pose_meets_constraints(model, options.constraints, q)) continue;
    workspace->candidates[found].q_rad = q;
    workspace->candidates[found].point_m = fk_tool_point(model, q);
    ++found;
  }
  *attempts = draws;
  return found == options.candidate_count ? Status::ok : Status::too_few_samples;
}

Status pool_identifiability(const RobotModel& model, const PlanOptions& options, PlanWorkspace* workspace,
                            IdentifiabilityReport* report, std::size_t* attempts) {
  Status status = generate_candidates(model, options, workspace, attempts);
  if (status != Status::ok) return status;
  const Span<const Sample> pool(workspace->candidates, options.candidate_count);
  status = accumulate_normal_equations(model, kIdentity, pool, PointLoss{}, &workspace->normal);
  if (status != Status::ok) return status;
  return analyze_identifiability(workspace->normal.jtwj, options.free_mask, options.identifiability_threshold,
                                 &workspace->identifiability, report);
}

Status evaluate_pose_set(const RobotModel& model, const RobotModel& objective, Span<const Sample> poses,
                         const PlanOptions& options, ParamMask objective_mask, const FullParams& scale,
                         PlanWorkspace* workspace, PoseSetQuality* quality) {
  Status status = accumulate_normal_equations(model, kIdentity, poses, PointLoss{}, &workspace->normal);
  if (status != Status::ok) return status;
  IdentifiabilityReport& report = quality->identifiability;
  status = analyze_identifiability(workspace->normal.jtwj, options.free_mask, options.identifiability_threshold,
                                   &workspace->identifiability, &report);
  if (status != Status::ok) return status;
  quality->condition = report.condition_after;
  quality->smallest_singular = report.singular_values_after[report.singular_count_after - 1];
  // sigma = noise sqrt(diag((J^T J)^-1)), factored Jacobi-scaled as the LM's sigmas are.
  FullParams kept_scale;
  scale_normal_matrix(workspace->normal.jtwj, report.kept_mask, 1.0, &workspace->information, &kept_scale);
  if (!cholesky_factor(workspace->information, report.kept_mask, &workspace->factor)) return Status::singular_system;
  FullParams inverse_diagonal;
  cholesky_inverse_diagonal(workspace->factor, &workspace->scratch, &inverse_diagonal);
  quality->sigma.setZero();
  for (int k = 0; k < kFullParamCount; ++k) {
    if (mask_has(report.kept_mask, k)) {
      quality->sigma(k) = options.noise_m * std::sqrt(std::fmax(inverse_diagonal(k), 0.0)) * kept_scale(k);
    }
  }
  return pose_set_criteria(objective, poses, scale, objective_mask, workspace, &quality->log_det,
                           &quality->prediction_variance)
             ? Status::ok
             : Status::singular_system;
}

double movej_time_s(const JointVector& from, const JointVector& to, const PlanOptions& options) {
  const double distance_rad = (to - from).cwiseAbs().maxCoeff();
  const double v = options.joint_speed_rad_s;
  const double a = options.joint_acceleration_rad_s2;
  if (distance_rad >= v * v / a) return distance_rad / v + v / a;  // trapezoid: cruise at v
  return 2.0 * std::sqrt(distance_rad / a);                        // triangle: never reaches v
}

double order_poses(JointVector* poses, std::size_t count, const PlanOptions& options) {
  if (count < 2) return 0.0;
  nearest_neighbour(poses, count, options);
  two_opt(poses, count, options);
  return path_time_s(poses, count, options);
}

Status plan_session(const RobotModel& model, const PlanOptions& options, PlanWorkspace* workspace, PlanResult* result) {
  if (!options_valid(options, model)) return Status::invalid_argument;
  if (!all_finite(to_params(model))) return Status::non_finite_input;
  *result = PlanResult{};
  Status status = Status::ok;
  // The objective differentiates the model with the tool off the flange axis (objective_model).
  const RobotModel objective = objective_model(model, options);
  if (options.criterion == PlanCriterion::i_optimal_workspace) {
    // The region the predictions should be good in: the same cell, any orientation.
    PlanOptions anywhere = options;
    anywhere.constraints.acceptance_rad = math::kPi;
    anywhere.constraints.orientation = PlanOrientation::facing_tracker;
    anywhere.seed = options.seed ^ 0x9e3779b97f4a7c15ULL;
    std::size_t draws = 0;
    status = generate_candidates(model, anywhere, workspace, &draws);
    if (status != Status::ok) return status;
    status = accumulate_normal_equations(objective, kIdentity,
                                         Span<const Sample>(workspace->candidates, options.candidate_count),
                                         PointLoss{}, &workspace->normal);
    if (status != Status::ok) return status;
    workspace->pool_information = workspace->normal.jtwj;
  }
  status = pool_identifiability(model, options, workspace, &result->pool, &result->attempts);
  if (status != Status::ok) return status;
  result->candidate_count = options.candidate_count;
  // The objective's parameters: what the pool identifies with the objective's tool.
  const Span<const Sample> pool(workspace->candidates, options.candidate_count);
  status = accumulate_normal_equations(objective, kIdentity, pool, PointLoss{}, &workspace->normal);
  if (status != Status::ok) return status;
  status = analyze_identifiability(workspace->normal.jtwj, options.free_mask, options.identifiability_threshold,
                                   &workspace->identifiability, &result->objective);
  if (status != Status::ok) return status;
  const ParamMask mask = result->objective.kept_mask;
  const FullParams scale = pool_scale(workspace->normal.jtwj, options.candidate_count, mask);
  if (options.criterion != PlanCriterion::i_optimal_workspace) workspace->pool_information = workspace->normal.jtwj;
  workspace->ridge = prior_ridge(model, workspace->normal.jtwj, scale, options);
  mean_scaled_information(workspace->pool_information, options.candidate_count, scale, mask,
                          &workspace->pool_information);

  status = select_poses(model, objective, options, scale, mask, workspace, result);
  if (status != Status::ok) return status;
  const Span<const Sample> selection(workspace->selected, options.pose_count);

  const Span<const Sample> first_draws(workspace->candidates, options.pose_count);  // random, same constraints
  status = evaluate_pose_set(model, objective, first_draws, options, mask, scale, workspace, &result->random);
  if (status != Status::ok) return status;
  status = evaluate_pose_set(model, objective, selection, options, mask, scale, workspace, &result->planned);
  if (status != Status::ok) return status;

  result->pose_count = options.pose_count;
  for (std::size_t i = 0; i < options.pose_count; ++i) result->poses[i] = workspace->selected[i].q_rad;
  result->unordered_travel_s = path_time_s(result->poses, result->pose_count, options);
  result->travel_s = order_poses(result->poses, result->pose_count, options);
  result->session_s = result->travel_s + static_cast<double>(result->pose_count) * options.dwell_s;
  return Status::ok;
}

}  // namespace hivecal
