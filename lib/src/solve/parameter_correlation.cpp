// Parameter correlations from the normal equations at a fit's result
// (solve/parameter_correlation.hpp).
#include "hivecal/solve/parameter_correlation.hpp"

#include <Eigen/Cholesky>

#include <cmath>

namespace hivecal {
namespace {

/// The inverse of the leading N x N block of `scaled` into *inverse (zero elsewhere). A rigid
/// model inverts only the 33 rigid parameters: the same pivots with or without the room for
/// compliance coefficients.
template <int N>
bool invert_leading(const NormalMatrix& scaled, NormalMatrix* inverse) {
  using Block = Eigen::Matrix<double, N, N>;
  const Eigen::LDLT<Block> ldlt(scaled.template topLeftCorner<N, N>());
  if (ldlt.info() != Eigen::Success) return false;
  inverse->setZero();
  inverse->template topLeftCorner<N, N>() = ldlt.solve(Block::Identity());
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
                            ? invert_leading<kFullParamCount>(scratch->scaled, correlation)
                            : invert_leading<kRigidParamCount>(scratch->scaled, correlation);
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
