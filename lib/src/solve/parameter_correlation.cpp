// Parameter correlations from the normal equations at a fit's result
// (solve/parameter_correlation.hpp).
#include "hivecal/solve/parameter_correlation.hpp"

#include <cmath>

#include "solve/kept_cholesky.hpp"

namespace hivecal {

Status parameter_correlations(const RobotModel& model, const RigidTransform& base_to_tracker,
                              Span<const Sample> samples, const PointLoss& loss, ParamMask kept,
                              CorrelationScratch* scratch, NormalMatrix* correlation) {
  if (scratch == nullptr || correlation == nullptr) return Status::invalid_argument;
  NormalEquations& eq = scratch->equations;
  eq.targets = Span<TargetBlock>(scratch->target_blocks, kMaxTargets - 1);
  const Status accumulated = accumulate_normal_equations(model, base_to_tracker, samples, loss, &eq, kept);
  if (accumulated != Status::ok) return accumulated;
  // Unit diagonal over `kept` (the inverse's scale is divided out below; the factor is better
  // conditioned), factored over the kept parameters only: the same pivots whatever the build's
  // capacity for joint terms.
  FullParams scale;
  scale_normal_matrix(eq.jtwj, kept, 1.0, &scratch->scaled, &scale);
  if (!cholesky_factor(scratch->scaled, kept, &scratch->factor)) return Status::singular_system;
  cholesky_inverse(scratch->factor, &scratch->inverse_factor, correlation);
  const FullParams variance = correlation->diagonal();
  for (int i = 0; i < kFullParamCount; ++i) {
    for (int j = 0; j < kFullParamCount; ++j) {
      const double d = std::sqrt(variance(i) * variance(j));
      (*correlation)(i, j) = mask_has(kept, i) && mask_has(kept, j) && d > 0.0 ? (*correlation)(i, j) / d : 0.0;
    }
  }
  return correlation->allFinite() ? Status::ok : Status::singular_system;
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
