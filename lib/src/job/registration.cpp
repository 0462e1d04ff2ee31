// Registration of a calibration on new samples, and its covariance carried through
// (hivecal/registration.hpp).
#include "hivecal/registration.hpp"

#include <Eigen/SVD>
#include <cmath>
#include <limits>
#include <utility>

#include "hivecal/model/rigid_fit.hpp"
#include "hivecal/solve/prediction_uncertainty.hpp"
#include "solve/kept_cholesky.hpp"

namespace hivecal {

const char* registration_fit_name(RegistrationFit fit) {
  return fit == RegistrationFit::frames ? "frames" : "base";
}

const char* registration_blunder_verdict_name(RegistrationBlunderVerdict verdict) {
  switch (verdict) {
    case RegistrationBlunderVerdict::none: return "none";
    case RegistrationBlunderVerdict::set_aside: return "set_aside";
    case RegistrationBlunderVerdict::model_error: return "model_error";
    case RegistrationBlunderVerdict::not_tested: return "not_tested";
  }
  return "?";
}

ParamMask registration_mask(RegistrationFit fit, const RobotModel& model) {
  ParamMask mask = 0;
  for (int axis = 0; axis < 3; ++axis) {
    mask |= param_bit(base_rotation_param_index(model, axis)) | param_bit(base_translation_param_index(model, axis));
    if (fit == RegistrationFit::frames) mask |= param_bit(tool_param_index(model, axis));
  }
  return fit == RegistrationFit::frames ? mask | kOtherTargetTools : mask;
}

namespace {

/// Points within this of their centroid coincide (RMS) [m].
constexpr double kCoincidentSpread_m = 1e-6;
/// Points whose second principal spread is below this share of the first lie on a line: the
/// rigid fit's kCollinearityThreshold on the variances, here on their square roots [-].
constexpr double kCollinearSpread = 1e-5;

/// The w-test's findings in one round: the failing fitted poses and the worst of them.
class FailingPoses final : public UnitTestVisitor {
 public:
  void on_unit(const UnitTest& t) override {
    if (!t.fitted || !t.rejected()) return;
    ++failing;
    if (t.w / t.critical_w > worst_ratio_) {
      worst_ratio_ = t.w / t.critical_w;
      worst = t;
    }
  }
  std::size_t failing = 0;  ///< fitted poses above their threshold [-]
  UnitTest worst;           ///< the one furthest above it (w / critical w)

 private:
  double worst_ratio_ = 0.0;
};

/// Moves samples [begin, begin + count) behind the others of samples[0, end), keeping both
/// groups' order.
void move_behind(Span<Sample> samples, std::size_t begin, std::size_t count, std::size_t end) {
  for (std::size_t moved = 0; moved < count; ++moved) {
    for (std::size_t k = begin; k + 1 < end; ++k) std::swap(samples[k], samples[k + 1]);
  }
}

/// Poses (runs of samples at equal joints) of `samples` [-].
std::size_t pose_count_of(Span<const Sample> samples) {
  std::size_t poses = 0;
  for (std::size_t begin = 0; begin < samples.size(); begin = pose_run_end(samples, begin)) ++poses;
  return poses;
}

/// The spread of the measured points: RMS distance from their centroid, and the second
/// principal spread over the first.
void point_spread(Span<const Sample> samples, RegistrationResult* result) {
  Vec3 mean = Vec3::Zero();
  for (const Sample& s : samples) mean += s.point_m;
  mean /= static_cast<double>(samples.size());
  Mat3 scatter = Mat3::Zero();
  for (const Sample& s : samples) scatter += (s.point_m - mean) * (s.point_m - mean).transpose();
  const Vec3 variances = Eigen::JacobiSVD<Mat3>(scatter).singularValues();  // decreasing
  result->spread_m = std::sqrt(scatter.trace() / static_cast<double>(samples.size()));
  result->collinearity = variances(0) > 0.0 ? std::sqrt(variances(1) / variances(0)) : 0.0;
}

/// Condition number of the column-scaled Jacobian of the estimated parameters: the square root
/// of that of their correlation matrix (the inverse of the scaled normal matrix).
double scaled_condition(const NormalMatrix& covariance, ParamMask estimated) {
  constexpr int kMax = kBaseParamCount + 3;  // base and target 1's tool point
  int index[kFullParamCount];
  const int count = mask_indices(estimated, index);
  Eigen::Matrix<double, kMax, kMax> correlation = Eigen::Matrix<double, kMax, kMax>::Identity();
  for (int a = 0; a < count && a < kMax; ++a) {
    for (int b = 0; b < count && b < kMax; ++b) {
      const double d = std::sqrt(covariance(index[a], index[a]) * covariance(index[b], index[b]));
      correlation(a, b) = d > 0.0 ? covariance(index[a], index[b]) / d : 0.0;
    }
  }
  const Eigen::Matrix<double, kMax, 1> values = Eigen::JacobiSVD<Eigen::Matrix<double, kMax, kMax>>(correlation)
                                                    .singularValues();  // unit padding: mean 1 lies within
  return values(kMax - 1) > 0.0 ? std::sqrt(values(0) / values(kMax - 1)) : std::numeric_limits<double>::infinity();
}

/// One fit of the registered parameters on `fitted`, its covariance and figures into *result.
Status fit_once(const RobotModel& calibrated, Span<const Sample> fitted, const RegistrationOptions& options,
                RegistrationWorkspace* ws, RegistrationResult* result) {
  RobotModel start = calibrated;
  RigidTransform start_base;
  const Status rigid = options.fit == RegistrationFit::frames ? fit_base_and_target_tools(fitted, &start, &start_base)
                                                              : fit_base_to_tracker(start, fitted, &start_base);
  if (rigid != Status::ok) return rigid;
  // Points that coincide to rounding pass the rigid fit's exact test (its scatter is rounding
  // noise): a tracker resolves no micrometre, so they place no base.
  point_spread(fitted, result);
  if (!(result->spread_m > kCoincidentSpread_m) || !(result->collinearity > kCollinearSpread)) {
    return Status::degenerate_geometry;
  }
  const ParamMask registered = registration_mask(options.fit, start);
  LmOptions lm = options.lm;
  lm.params = LmParamSet::custom;
  lm.custom_mask = registered & ~kOtherTargetTools;
  lm.other_target_tools = options.fit == RegistrationFit::frames;
  LmResult& fit = ws->fit;
  const Status status = calibrate_lm(start, &start_base, fitted, lm, &ws->lm, &fit);
  if (status != Status::ok) return status;
  result->model = fit.model;
  result->base_to_tracker = fit.base_to_tracker;
  result->estimated = fit.identifiability.kept_mask | (registered & kOtherTargetTools);
  result->dropped = lm.custom_mask & ~fit.identifiability.kept_mask;
  result->huber_threshold_m = fit.huber_threshold_m;
  result->rms_m = fit.rms_m;
  result->iterations = fit.iterations;
  result->termination = fit.termination;
  result->fitted_samples = fitted.size();
  result->fitted_poses = pose_count_of(fitted);
  int dof = 0;
  const Status covariance =
      parameter_covariance(fit.model, fit.base_to_tracker, fitted, PointLoss{fit.huber_threshold_m}, result->estimated,
                           &ws->covariance, &result->covariance, &dof);
  if (covariance != Status::ok) return covariance;
  result->residual_dof = dof;
  result->residual_sigma_m = fit.residual_sigma_m;
  for (int axis = 0; axis < 3; ++axis) {
    const int r = base_rotation_param_index(fit.model, axis);
    const int t = base_translation_param_index(fit.model, axis);
    const int tool = tool_param_index(fit.model, axis);
    result->rotation_sigma_rad(axis) = std::sqrt(result->covariance(r, r));
    result->translation_sigma_m(axis) = std::sqrt(result->covariance(t, t));
    result->tool_sigma_m(axis) = std::sqrt(result->covariance(tool, tool));
  }
  for (int k = 0; k < kMaxTargets - 1; ++k) result->other_tools_sigma_m[k] = fit.other_tools_sigma_m[k];
  double variance_sum_m2 = 0.0;
  for (std::size_t begin = 0; begin < fitted.size(); begin = pose_run_end(fitted, begin)) {
    const Sample& s = fitted[begin];
    const double sigma_m = prediction_sigma_m(
        fit.model, fit.base_to_tracker, s.q_rad, s.target, result->covariance, result->estimated & ~kOtherTargetTools,
        PredictionFrame::tracker, s.target > 0 ? fit.other_tools_sigma_m[s.target - 1] : Vec3(Vec3::Zero()));
    variance_sum_m2 += sigma_m * sigma_m;
  }
  result->point_sigma_m = std::sqrt(variance_sum_m2 / static_cast<double>(result->fitted_poses));
  result->condition = scaled_condition(result->covariance, result->estimated & ~kOtherTargetTools);
  unsigned weakness = 0;
  if (result->collinearity < kRegistrationCollinearRatio) weakness |= kRegistrationNearlyCollinear;
  if (result->spread_m < kRegistrationMinSpread_m) weakness |= kRegistrationSmallSpread;
  if (dof < kRegistrationMinResidualDof) weakness |= kRegistrationFewResiduals;
  if (!(result->condition <= kRegistrationMaxCondition)) weakness |= kRegistrationIllConditioned;
  if (result->dropped != 0) weakness |= kRegistrationUndetermined;
  result->weakness = weakness;
  return Status::ok;
}

/// Clears the fields a registration writes, in place (a RegistrationResult is ~45 kB).
void clear(RegistrationResult* result) {
  result->covariance.setZero();
  result->estimated = 0;
  result->dropped = 0;
  result->weakness = 0;
  result->blunder_count = 0;
  result->failing_poses = 0;
  result->verdict = RegistrationBlunderVerdict::not_tested;
}

}  // namespace

Status register_frames(const RobotModel& calibrated, Span<Sample> samples, const RegistrationOptions& options,
                       RegistrationWorkspace* workspace, RegistrationResult* result) {
  if (workspace == nullptr || result == nullptr || !(options.max_blunder_share >= 0.0)) {
    return Status::invalid_argument;
  }
  if (samples.empty()) return Status::dataset_empty;
  clear(result);
  result->fit = options.fit;
  std::size_t fitted_end = samples.size();
  const bool grouped = target_count(Span<const Sample>(samples.data(), samples.size())) > 1;
  std::size_t limit = 0;
  for (;;) {
    const Span<const Sample> fitted(samples.data(), fitted_end);
    const Status status = fit_once(calibrated, fitted, options, workspace, result);
    if (status != Status::ok) return status;
    if (!options.find_blunders) return Status::ok;
    FailingPoses failing;
    BlunderTestSummary summary;
    const Status tested =
        test_for_blunders(result->model, result->base_to_tracker, fitted, Span<const Sample>(), result->estimated,
                          PointLoss{}, options.blunder_test, &workspace->reliability, &failing, &summary);
    if (tested != Status::ok) {  // too little redundancy: what was set aside stays so
      if (result->blunder_count == 0) result->verdict = RegistrationBlunderVerdict::not_tested;
      return Status::ok;
    }
    if (result->blunder_count == 0) {
      const auto share =
          static_cast<std::size_t>(options.max_blunder_share * static_cast<double>(summary.fitted_units));
      limit = share > 0 ? share : 1;
      if (limit > kMaxRegistrationBlunders) limit = kMaxRegistrationBlunders;
      result->failing_poses = failing.failing;
      if (failing.failing > limit) {
        result->verdict = RegistrationBlunderVerdict::model_error;
        return Status::ok;
      }
    }
    if (failing.failing == 0) {
      result->verdict =
          result->blunder_count > 0 ? RegistrationBlunderVerdict::set_aside : RegistrationBlunderVerdict::none;
      return Status::ok;
    }
    // The worst pose goes, unless the limit is reached or too few poses would remain.
    const std::size_t begin = failing.worst.position;
    const std::size_t end = unit_end(fitted, begin, grouped);
    if (result->blunder_count >= limit || result->fitted_poses <= 3) {
      result->verdict = RegistrationBlunderVerdict::set_aside;
      return Status::ok;
    }
    RegistrationBlunder& b = result->blunders[result->blunder_count++];
    b.index = failing.worst.index;
    b.samples = static_cast<std::uint32_t>(end - begin);
    b.w = failing.worst.w;
    b.critical_w = failing.worst.critical_w;
    b.residual_m = failing.worst.residual_m;
    move_behind(samples, begin, end - begin, fitted_end);
    fitted_end -= end - begin;
  }
}

Status carry_covariance(const RegistrationResult& registration, Span<const Sample> fitted, ParamMask estimated,
                        const NormalMatrix& calibrated_covariance, CorrelationScratch* scratch,
                        NormalMatrix* covariance, ParamMask* carried_estimated) {
  if (scratch == nullptr || covariance == nullptr || carried_estimated == nullptr) return Status::invalid_argument;
  const ParamMask registered = registration.estimated;
  const ParamMask others = estimated & ~registered & ~kOtherTargetTools;
  const ParamMask columns = (others | registered) & ~kOtherTargetTools;
  NormalEquations& eq = scratch->equations;
  eq.targets = Span<TargetBlock>(scratch->target_blocks, kMaxTargets - 1);
  // The registration's normal equations (its other tool points eliminated when it fitted them).
  const Status accumulated = accumulate_normal_equations(registration.model, registration.base_to_tracker, fitted,
                                                         PointLoss{registration.huber_threshold_m}, &eq,
                                                         columns | (registered & kOtherTargetTools));
  if (accumulated != Status::ok) return accumulated;
  const ParamMask b_mask = registered & ~kOtherTargetTools;
  FullParams scale;
  scale_kept_block(eq.jtwj, b_mask, &scratch->scaled, &scale);
  if (!cholesky_factor(scratch->scaled, b_mask, &scratch->factor)) return Status::singular_system;
  int b_index[kFullParamCount];
  const int b_count = mask_indices(b_mask, b_index);
  int t_index[kFullParamCount];
  const int t_count = mask_indices(others, t_index);
  // G = -H_BB^-1 H_B,theta column by column (scaled: H^-1 = S A^-1 S), into the rows of `scaled`.
  NormalMatrix& gain = scratch->scaled;  // read by the factor no more
  for (int j = 0; j < t_count; ++j) {
    FullParams column = FullParams::Zero();
    for (int a = 0; a < b_count; ++a) column(b_index[a]) = eq.jtwj(b_index[a], t_index[j]) * scale(b_index[a]);
    FullParams solved;
    cholesky_solve(scratch->factor, column, &solved);
    for (int a = 0; a < b_count; ++a) gain(b_index[a], t_index[j]) = -solved(b_index[a]) * scale(b_index[a]);
  }
  // G C_tt into `inverse_factor`'s B rows.
  NormalMatrix& gain_cov = scratch->inverse_factor;
  for (int a = 0; a < b_count; ++a) {
    for (int j = 0; j < t_count; ++j) {
      double sum = 0.0;
      for (int k = 0; k < t_count; ++k)
        sum += gain(b_index[a], t_index[k]) * calibrated_covariance(t_index[k], t_index[j]);
      gain_cov(b_index[a], t_index[j]) = sum;
    }
  }
  if (covariance != &calibrated_covariance) *covariance = calibrated_covariance;
  for (int i = 0; i < kFullParamCount; ++i) {  // nothing outside estimated | B
    if (mask_has(columns, i)) continue;
    covariance->row(i).setZero();
    covariance->col(i).setZero();
  }
  for (int a = 0; a < b_count; ++a) {
    const int i = b_index[a];
    for (int j = 0; j < t_count; ++j) {
      (*covariance)(i, t_index[j]) = gain_cov(i, t_index[j]);
      (*covariance)(t_index[j], i) = gain_cov(i, t_index[j]);
    }
    for (int c = 0; c < b_count; ++c) {
      const int k = b_index[c];
      double sum = registration.covariance(i, k);
      for (int j = 0; j < t_count; ++j) sum += gain_cov(i, t_index[j]) * gain(k, t_index[j]);
      (*covariance)(i, k) = sum;
    }
  }
  *carried_estimated = columns;
  return covariance->allFinite() ? Status::ok : Status::singular_system;
}

}  // namespace hivecal
