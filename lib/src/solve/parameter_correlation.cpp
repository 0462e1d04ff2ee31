// Parameter correlations and covariance from the normal equations at a fit's result
// (solve/parameter_correlation.hpp).
#include "hivecal/solve/parameter_correlation.hpp"

#include <cmath>

#include "solve/kept_cholesky.hpp"

namespace hivecal {

namespace {

/// The normal equations of `samples` at the point over `kept` into scratch->equations.
Status accumulate_kept(const RobotModel& model, const RigidTransform& base_to_tracker, Span<const Sample> samples,
                       const PointLoss& loss, ParamMask kept, CorrelationScratch* scratch) {
  NormalEquations& eq = scratch->equations;
  eq.targets = Span<TargetBlock>(scratch->target_blocks, kMaxTargets - 1);
  return accumulate_normal_equations(model, base_to_tracker, samples, loss, &eq, kept);
}

/// The inverse of the Jacobi-scaled kept block of scratch->equations into *scaled_inverse,
/// (S A S)^-1 with S = *scale: A^-1 = S (S A S)^-1 S over the kept parameters.
/// With `prior_weights` (the prior's P, diagonal [m^2/unit^2]), (S (A + P) S)^-1.
Status scaled_kept_inverse(ParamMask kept, CorrelationScratch* scratch, NormalMatrix* scaled_inverse, FullParams* scale,
                           const FullParams* prior_weights = nullptr) {
  // Unit diagonal over `kept` (the factor is better conditioned), factored over the kept
  // parameters only: the same pivots whatever the build's capacity for joint terms.
  scale_normal_matrix(scratch->equations.jtwj, kept, 1.0, &scratch->scaled, scale);
  if (prior_weights != nullptr) {
    for (int i = 0; i < kFullParamCount; ++i)
      if (mask_has(kept, i)) scratch->scaled(i, i) += (*prior_weights)(i) * (*scale)(i) * (*scale)(i);
  }
  if (!cholesky_factor(scratch->scaled, kept, &scratch->factor)) return Status::singular_system;
  cholesky_inverse(scratch->factor, &scratch->inverse_factor, scaled_inverse);
  return Status::ok;
}

}  // namespace

Status parameter_correlations(const RobotModel& model, const RigidTransform& base_to_tracker,
                              Span<const Sample> samples, const PointLoss& loss, ParamMask kept,
                              CorrelationScratch* scratch, NormalMatrix* correlation) {
  if (scratch == nullptr || correlation == nullptr) return Status::invalid_argument;
  FullParams scale;  // divided out below with the rest of the diagonal
  Status status = accumulate_kept(model, base_to_tracker, samples, loss, kept, scratch);
  if (status == Status::ok) status = scaled_kept_inverse(kept, scratch, correlation, &scale);
  if (status != Status::ok) return status;
  const FullParams variance = correlation->diagonal();
  for (int i = 0; i < kFullParamCount; ++i) {
    for (int j = 0; j < kFullParamCount; ++j) {
      const double d = std::sqrt(variance(i) * variance(j));
      (*correlation)(i, j) = mask_has(kept, i) && mask_has(kept, j) && d > 0.0 ? (*correlation)(i, j) / d : 0.0;
    }
  }
  return correlation->allFinite() ? Status::ok : Status::singular_system;
}

Status parameter_covariance(const RobotModel& model, const RigidTransform& base_to_tracker, Span<const Sample> samples,
                            const PointLoss& loss, ParamMask kept, CorrelationScratch* scratch,
                            NormalMatrix* covariance, int* residual_dof, const LmPrior& prior) {
  if (scratch == nullptr || covariance == nullptr) return Status::invalid_argument;
  const Status accumulated = accumulate_kept(model, base_to_tracker, samples, loss, kept, scratch);
  if (accumulated != Status::ok) return accumulated;
  const NormalEquations& eq = scratch->equations;
  int eliminated = 0;  // the other targets' tool points, 3 parameters each (as LM counts them)
  for (const TargetBlock& block : eq.targets) eliminated += block.count > 0 ? 3 : 0;
  const int dof = 3 * static_cast<int>(eq.count) - mask_count(kept) - eliminated;
  if (dof <= 0) return Status::too_few_samples;
  const double variance_m2 = eq.weighted_squares_m2 / static_cast<double>(dof);
  // The prior's pseudo-observations weigh as in LM: variance factor / tolerance^2.
  FullParams prior_weights = FullParams::Zero();
  for (int i = 0; i < kFullParamCount; ++i) {
    const double sigma = lm_prior_sigma(prior, i);
    if (sigma > 0.0) prior_weights(i) = variance_m2 / (sigma * sigma);
  }
  FullParams scale;
  const Status inverted = scaled_kept_inverse(kept, scratch, covariance, &scale, &prior_weights);
  if (inverted != Status::ok) return inverted;
  for (int i = 0; i < kFullParamCount; ++i) {
    for (int j = 0; j < kFullParamCount; ++j) {
      const bool both = mask_has(kept, i) && mask_has(kept, j);
      (*covariance)(i, j) = both ? (*covariance)(i, j) * scale(i) * scale(j) * variance_m2 : 0.0;
    }
  }
  if (residual_dof != nullptr) *residual_dof = dof;
  return covariance->allFinite() ? Status::ok : Status::singular_system;
}

CorrelationPartner strongest_correlation(const NormalMatrix& correlation, int k) {
  CorrelationPartner partner;
  for (int other = 0; other < kFullParamCount; ++other) {
    if (other != k && std::fabs(correlation(k, other)) > std::fabs(partner.correlation)) {
      partner.index = other;
      partner.correlation = correlation(k, other);
    }
  }
  return partner;
}

}  // namespace hivecal
