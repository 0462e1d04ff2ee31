// Correlations and covariance of the estimated parameters of a least-squares fit: the
// (normalised, or scaled by the residual variance) inverse of its normal equations at the result. Which parameters the
// data cannot tell apart (|rho| near 1) explains a large move or a dropped parameter (docs/solvers-lm.md, "Parameter
// correlations"). Kept out of the job's result: the matrix and its scratch are five
// NormalMatrix (~43 kB each at the hosted capacity), beyond the firmware's RAM; a caller that
// wants it supplies the storage.
#pragma once

#include "hivecal/core/status.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/solve/normal_equations.hpp"

namespace hivecal {

/// Scratch of parameter_correlations (none of it on the stack): the normal equations, their
/// eliminated target blocks, the scaled matrix, its Cholesky factor over the kept parameters
/// and that factor's inverse.
struct CorrelationScratch {
  NormalEquations equations;                   ///< J^T W J at the result [m^2/unit^2]
  TargetBlock target_blocks[kMaxTargets - 1];  ///< targets 2.. eliminated as in LM
  NormalMatrix scaled;                         ///< unit-diagonal J^T W J [-]
  KeptCholesky factor;                         ///< U^T U = the kept block of `scaled` [-]
  NormalMatrix inverse_factor;                 ///< U^-1 [-]
};

/// The correlation matrix of the parameters in `kept` (LmResult::identifiability.kept_mask)
/// at `model` / `base_to_tracker`, from the normal equations of `samples` under `loss` (the
/// ones LM's sigmas come from): rho_ij = C_ij / sqrt(C_ii C_jj), C = (J^T W J)^-1 over the
/// kept parameters. Entries of parameters not kept are 0. Errors: dataset_empty, non_finite_input,
/// singular_system (the kept parameters' matrix is not positive definite).
Status parameter_correlations(const RobotModel& model, const RigidTransform& base_to_tracker,
                              Span<const Sample> samples, const PointLoss& loss, ParamMask kept,
                              CorrelationScratch* scratch, NormalMatrix* correlation);

/// The covariance of the parameters in `kept` at `model` / `base_to_tracker` from `samples`
/// under `loss`: C = sigma_hat^2 (J^T W J)^-1 over the kept parameters (targets 2.. whose
/// tool points `kept` estimates, kOtherTargetTools, eliminated as LM does: C is their
/// marginal), sigma_hat^2 = sum w |r|^2 / (3 N - p - 3 per eliminated target), LM's residual
/// variance; sqrt(C_kk) is LmResult::sigma(k) at LM's result [m^2], [m rad] or [rad^2].
/// Entries of parameters not kept are 0. *residual_dof (optional): that 3 N - p - ... [-].
/// With the fit's `prior`, the posterior: C = sigma_hat^2 (J^T W J + P)^-1, P = sigma_hat^2 /
/// tolerance^2 on each toleranced parameter, as LM weighs it (a direction the data do not
/// determine keeps about its tolerance).
/// Errors: those of parameter_correlations, too_few_samples (no residual degree of freedom).
Status parameter_covariance(const RobotModel& model, const RigidTransform& base_to_tracker, Span<const Sample> samples,
                            const PointLoss& loss, ParamMask kept, CorrelationScratch* scratch,
                            NormalMatrix* covariance, int* residual_dof = nullptr, const LmPrior& prior = LmPrior{});

/// The parameter most correlated with parameter k among the kept ones (k itself excluded),
/// and that correlation [-]. -1 and 0 when none is kept or every correlation is 0.
struct CorrelationPartner {
  int index = -1;            ///< full parameter index of the partner; -1: none
  double correlation = 0.0;  ///< rho between parameter k and the partner [-]
};
CorrelationPartner strongest_correlation(const NormalMatrix& correlation, int k);

}  // namespace hivecal
