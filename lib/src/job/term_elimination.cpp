// The joint-term test's refits in closed form (term_elimination.hpp).
#include "job/term_elimination.hpp"

#include <cmath>

#include "hivecal/model/full_params.hpp"
#include "solve/kept_cholesky.hpp"

namespace hivecal::detail {
namespace {

/// The next joint term to fix among `candidates`: the largest coefficient beyond
/// kMaxJointTermCoefficient, else the least significant below its level; -1 when none is.
int next_term(const RobotModel& reference, const FullParams& value, const FullParams& delta, const FullParams& variance,
              ParamMask candidates, double significance_t, double compliance_t, int dof) {
  int worst = -1;
  double worst_abs = kMaxJointTermCoefficient;
  for (int t = 0; t < reference.compliance.term_count; ++t) {
    const int i = compliance_param_index(reference, t);
    if (mask_has(candidates, i) && std::fabs(value(i)) > worst_abs) {
      worst_abs = std::fabs(value(i));
      worst = i;
    }
  }
  if (worst >= 0) return worst;
  double weakest_ratio = 1.0;
  for (int t = 0; t < reference.compliance.term_count; ++t) {
    const int i = compliance_param_index(reference, t);
    if (!mask_has(candidates, i) || !(variance(i) > 0.0)) continue;
    const double level = parameter_significance_level(reference, i, significance_t, compliance_t, dof);
    const double ratio = std::fabs(delta(i)) / std::sqrt(variance(i)) / level;  // below 1: not significant
    if (ratio < weakest_ratio) {
      weakest_ratio = ratio;
      worst = i;
    }
  }
  return worst;
}

/// (J^T W J + P)^-1 over `params` from the normal equations in ws->normal, unscaled, into
/// ws->scaled [unit^2/m^2]; false when they are not positive definite.
// Not inlined, nor the elimination: their vectors stay off the stack while the sums run.
[[gnu::noinline]] bool invert_normal_matrix(ParamMask params, ReliabilityWorkspace* ws) {
  FullParams scale;
  scale_normal_matrix(ws->normal.jtwj, params, 1.0, &ws->scaled, &scale);
  if (!cholesky_factor(ws->scaled, params, &ws->factor)) return false;
  NormalMatrix& covariance = ws->scaled;
  cholesky_inverse(ws->factor, &ws->normal.jtwj, &covariance);
  int index[kFullParamCount];
  const int count = mask_indices(params, index);
  for (int a = 0; a < count; ++a) {
    for (int b = 0; b < count; ++b) covariance(index[a], index[b]) *= scale(index[a]) * scale(index[b]);
  }
  return true;
}

/// The fixes after `first`, on the covariance in `covariance` (invert_normal_matrix's).
[[gnu::noinline]] ParamMask eliminate(const FoldFit& fit, const RobotModel& reference, ParamMask params, int first,
                                      double significance_t, double compliance_t, double sigma_m, int dof,
                                      NormalMatrix& covariance) {
  ParamMask fixed = param_bit(first);
  int index[kFullParamCount];
  const int count = mask_indices(params, index);
  FullParams value = FullParams::Zero();
  FullParams delta = FullParams::Zero();
  for (int k = 0; k < count; ++k) {
    value(index[k]) = full_param_value(*fit.model, index[k]);
    delta(index[k]) = value(index[k]) - full_param_value(reference, index[k]);
  }
  double squares_m2 = sigma_m * sigma_m * static_cast<double>(dof);
  ParamMask candidates = params & compliance_params_mask(reference.joint_count, kMaxComplianceTerms);
  for (int k = first; k >= 0;) {
    // Fixing k at its reference: the others move by -C[:,k] delta_k / C_kk, their covariance
    // loses C[:,k] C[k,:] / C_kk, the residual sum gains delta_k^2 / C_kk.
    const double c_kk = covariance(k, k);
    if (!(c_kk > 0.0)) break;
    const double shift = delta(k) / c_kk;
    squares_m2 += delta(k) * shift;
    FullParams column = FullParams::Zero();
    for (int a = 0; a < count; ++a) column(index[a]) = covariance(index[a], k);
    for (int a = 0; a < count; ++a) {
      delta(index[a]) -= column(index[a]) * shift;
      value(index[a]) -= column(index[a]) * shift;
    }
    for (int a = 0; a < count; ++a) {
      const double ratio = column(index[a]) / c_kk;
      for (int b = 0; b < count; ++b) covariance(index[a], index[b]) -= ratio * column(index[b]);
    }
    candidates &= ~param_bit(k);
    ++dof;
    const double variance_m2 = dof > 0 ? squares_m2 / static_cast<double>(dof) : 0.0;
    FullParams variance = FullParams::Zero();
    for (int a = 0; a < count; ++a) variance(index[a]) = variance_m2 * covariance(index[a], index[a]);
    k = next_term(reference, value, delta, variance, candidates, significance_t, compliance_t, dof);
    if (k >= 0) fixed |= param_bit(k);
  }
  return fixed;
}

}  // namespace

Status linearised_term_fixes(const FoldFit& fit, const RobotModel& reference, Span<const Sample> samples,
                             const PointLoss& loss, int first, double significance_t, double compliance_t,
                             double sigma_m, int dof, CalibrationWorkspaceBase& workspace, ParamMask* fixed) {
  *fixed = param_bit(first);
  const ParamMask params = fit.estimated & ~kOtherTargetTools;
  ReliabilityWorkspace* ws = workspace.open_reliability();
  ws->normal.targets = Span<TargetBlock>(ws->blocks, kMaxTargets - 1);  // the other tool points, eliminated
  Status status = fit_normal_equations(fit, samples, loss, fit.estimated, &ws->normal);
  if (status == Status::ok && !invert_normal_matrix(params, ws)) status = Status::singular_system;
  if (status == Status::ok) {
    *fixed = eliminate(fit, reference, params, first, significance_t, compliance_t, sigma_m, dof, ws->scaled);
  }
  workspace.close();
  return status;
}

}  // namespace hivecal::detail
