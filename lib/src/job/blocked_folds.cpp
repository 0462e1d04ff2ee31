// Joint terms beyond the training poses' joint ranges (blocked_folds.hpp): each joint's lowest
// and highest readings held out in turn and predicted by the fit of the other poses.
#include "job/blocked_folds.hpp"

#include <cmath>

#include "hivecal/core/math.hpp"
#include "hivecal/model/full_params.hpp"
#include "solve/kept_cholesky.hpp"

namespace hivecal::detail {
namespace {

/// Bisection steps for a fold's threshold: the interval of the joint's readings halved this often
/// is far below any two distinct readings' distance [-].
constexpr int kThresholdSteps = 60;

/// Training samples whose joint `joint` reads at most `threshold_rad` (`low`) or at least it [-].
std::size_t count_beyond(Span<const Sample> train, int joint, double threshold_rad, bool low) {
  std::size_t count = 0;
  for (const Sample& s : train) count += (low ? s.q_rad(joint) <= threshold_rad : s.q_rad(joint) >= threshold_rad);
  return count;
}

/// The reading of joint `joint` that bounds its lowest (`low`) or highest `wanted` training
/// samples: the smallest (largest) threshold with at least `wanted` samples at or beyond it,
/// by bisection over the readings' range (the samples of a pose share their joints: a
/// threshold never splits a pose) [rad].
double fold_threshold_rad(Span<const Sample> train, int joint, std::size_t wanted, bool low) {
  double lowest = train[0].q_rad(joint);
  double highest = lowest;
  for (const Sample& s : train) {
    lowest = std::fmin(lowest, s.q_rad(joint));
    highest = std::fmax(highest, s.q_rad(joint));
  }
  double inside = low ? highest : lowest;  // holds at least `wanted` beyond
  double outside = low ? lowest : highest;
  for (int step = 0; step < kThresholdSteps; ++step) {
    const double middle = 0.5 * (inside + outside);
    if (count_beyond(train, joint, middle, low) >= wanted) {
      inside = middle;
    } else {
      outside = middle;
    }
  }
  return inside;
}

/// Moves the training samples (positions [first, end) of the dataset) that `beyond` accepts to
/// the front (`front`) or the back of that range by exchanges (Hoare's partition); returns how
/// many it accepts.
template <typename Beyond>
std::size_t gather(DatasetBase* dataset, std::size_t first, std::size_t end, bool front, Beyond beyond) {
  std::size_t i = first;
  std::size_t k = end;
  const auto wanted_at_i = [&](std::size_t p) { return beyond(dataset->samples()[p]) == front; };
  while (true) {
    while (i < k && wanted_at_i(i)) ++i;
    while (i < k && !wanted_at_i(k - 1)) --k;
    if (i >= k) break;
    dataset->swap_samples(i, k - 1);
    ++i;
    --k;
  }
  return front ? i - first : end - i;
}

/// One fold: its normal equations `fold` (at the fit, in `ws->normal`) taken from the whole
/// set's with the prior (`ws->scaled`, `whole_gradient`), the fit of the others by one
/// Gauss-Newton step, and the fold's samples predicted by it; false when that system is not
/// positive definite (the others do not determine the estimated parameters).
// Not inlined: its vectors stay off the stack while the normal equations are summed (the
// firmware's stack budget).
[[gnu::noinline]] bool predict_fold(const FoldFit& fit, ParamMask columns, const FullParams& whole_gradient,
                                    Span<const Sample> fold, ReliabilityWorkspace* ws, RobotModel* moved, double* sum_m,
                                    double* squares_m2) {
  NormalMatrix& system = ws->normal.jtwj;  // the others' normal matrix, in place of the fold's
  int index[kFullParamCount];
  const int count = mask_indices(columns, index);
  for (int jb = 0; jb < count; ++jb) {
    const int b = index[jb];
    for (int ja = 0; ja < count; ++ja) system(index[ja], b) = ws->scaled(index[ja], b) - system(index[ja], b);
  }
  FullParams scale;
  scale_kept_block(system, columns, &system, &scale);
  if (!cholesky_factor(system, columns, &ws->factor)) return false;
  FullParams rhs;  // the others' gradient, scaled; then the step
  rhs.setZero();
  for (int k = 0; k < count; ++k) {
    const int i = index[k];
    rhs(i) = (ws->normal.jtwr(i) - whole_gradient(i)) * scale(i);
  }
  FullParams step;
  cholesky_solve(ws->factor, rhs, &step);
  bool finite = true;
  for (int i = 0; i < kFullParamCount; ++i) {
    step(i) = mask_has(columns, i) ? step(i) * scale(i) : 0.0;
    finite = finite && math::is_finite(step(i));
  }
  if (!finite) return false;
  *moved = *fit.model;
  RigidTransform base = *fit.base;
  apply_full_increment(step, moved, &base);
  *sum_m = 0.0;
  *squares_m2 = 0.0;
  for (const Sample& s : fold) {
    const double error_m = (base.apply(fk_sample_point(*moved, s)) - s.point_m).norm();
    *sum_m += error_m;
    *squares_m2 += error_m * error_m;
  }
  return math::is_finite(*squares_m2);
}

}  // namespace

Status fit_normal_equations(const FoldFit& fit, Span<const Sample> samples, const PointLoss& loss, ParamMask columns,
                            NormalEquations* out) {
  const Status status = accumulate_normal_equations(*fit.model, *fit.base, samples, loss, out, columns);
  if (status != Status::ok || fit.prior.nominal == nullptr) return status;
  const ModelParams p = to_params(*fit.model);
  const ModelParams nominal = to_params(*fit.prior.nominal);
  for (int i = 0; i < model_param_count(*fit.model); ++i) {
    const double sigma = lm_prior_sigma(fit.prior, i);
    if (!mask_has(columns, i) || !(sigma > 0.0)) continue;
    const double weight = fit.variance_m2 / (sigma * sigma);
    out->jtwj(i, i) += weight;
    out->jtwr(i) += weight * (p(i) - nominal(i));
  }
  return Status::ok;
}

Status blocked_fold_errors(DatasetBase* dataset, const FoldFit& fit, const PointLoss& loss,
                           CalibrationWorkspaceBase& workspace, FoldErrors* out) {
  *out = FoldErrors{};
  const std::size_t n = dataset->train().size();
  const auto wanted = static_cast<std::size_t>(kBlockedFoldShare * static_cast<double>(n) + 0.5);
  if (wanted == 0 || wanted >= n) return Status::ok;  // nothing to hold out: no fold solved
  // The other targets' tool points stay at the fit's (not eliminated): the sums then add up.
  const ParamMask columns = fit.estimated & ~kOtherTargetTools;
  ReliabilityWorkspace* ws = workspace.open_reliability();
  RobotModel& moved = workspace.lm_start();  // a fold's fit (not on the stack)
  Status status = fit_normal_equations(fit, dataset->train(), loss, columns, &ws->normal);
  const FullParams whole_gradient = ws->normal.jtwr;  // with the prior's pull
  ws->scaled = ws->normal.jtwj;                       // with the prior's weights
  for (int joint = 0; status == Status::ok && joint < fit.model->joint_count; ++joint) {
    for (int end = 0; end < 2 && status == Status::ok; ++end) {
      const bool low = end == 0;
      const double threshold_rad = fold_threshold_rad(dataset->train(), joint, wanted, low);
      const std::size_t count = gather(dataset, 0, n, low, [&](const Sample& s) {
        return low ? s.q_rad(joint) <= threshold_rad : s.q_rad(joint) >= threshold_rad;
      });
      if (count == 0 || count >= n) continue;
      const Span<const Sample> fold = dataset->train().subspan(low ? 0 : n - count, count);
      status = accumulate_normal_equations(*fit.model, *fit.base, fold, loss, &ws->normal, columns);
      if (status != Status::ok) break;
      double sum_m = 0.0;
      double squares_m2 = 0.0;
      out->solved[joint][end] = predict_fold(fit, columns, whole_gradient, fold, ws, &moved, &sum_m, &squares_m2);
      out->sum_m[joint][end] = out->solved[joint][end] ? sum_m : 0.0;
      out->squares_m2[joint][end] = out->solved[joint][end] ? squares_m2 : 0.0;
      out->count[joint][end] = count;
    }
  }
  workspace.close();
  const Status restored = dataset->restore_split();
  return status != Status::ok ? status : restored;
}

}  // namespace hivecal::detail
