// Parameter correlations from the normal equations at a fit's result
// (solve/parameter_correlation.hpp).
#include "hivecal/solve/parameter_correlation.hpp"

#include <cmath>

namespace hivecal {
namespace {

/// The inverse of the leading N x N block of `scaled` into *inverse (zero elsewhere), through
/// *factor (in the caller's scratch: a 37 x 37 factor and its solve are ~33 kB of stack
/// otherwise). A rigid model inverts only the 33 rigid parameters: the same pivots with or
/// without the room for compliance coefficients.
template <int N, typename Factor>
bool invert_leading(const NormalMatrix& scaled, Factor* factor, NormalMatrix* inverse) {
  using Block = Eigen::Matrix<double, N, N>;
  factor->compute(scaled.template topLeftCorner<N, N>());
  if (factor->info() != Eigen::Success) return false;
  inverse->setZero();
  inverse->template topLeftCorner<N, N>() = factor->solve(Block::Identity());
  return true;
}

}  // namespace

Status parameter_correlations(const RobotModel& model, const RigidTransform& base_to_tracker,
                              Span<const Sample> samples, const PointLoss& loss, ParamMask kept,
                              CorrelationScratch* scratch, NormalMatrix* correlation) {
  if (scratch == nullptr || correlation == nullptr) return Status::invalid_argument;
  NormalEquations& eq = scratch->equations;
  eq.targets = Span<TargetBlock>(scratch->target_blocks, kMaxTargets - 1);
  const Status accumulated = accumulate_normal_equations(model, base_to_tracker, samples, loss, &eq, kept);
  if (accumulated != Status::ok) return accumulated;
  FullParams scale;
  scale_normal_matrix(eq.jtwj, kept, 1.0, &scratch->scaled, &scale);  // unit diagonal; identity outside `kept`
  const bool inverted = model.compliance.term_count > 0
                            ? invert_leading<kFullParamCount>(scratch->scaled, &scratch->full_factor, correlation)
                            : invert_leading<kRigidParamCount>(scratch->scaled, &scratch->rigid_factor, correlation);
  if (!inverted) return Status::singular_system;
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
