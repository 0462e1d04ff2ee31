// Correlations of the estimated parameters of a least-squares fit: the normalised inverse of
// its normal equations at the result. Which parameters the data cannot tell apart (|rho|
// near 1) explains a large move or a dropped parameter (docs/solvers-lm.md, "Parameter
// correlations"). Kept out of the job's result: the matrix and its scratch are ~54 kB, far
// beyond the firmware's RAM; a caller that wants it supplies the storage.
#pragma once

#include <Eigen/Cholesky>

#include "hivecal/core/status.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/solve/normal_equations.hpp"

namespace hivecal {

/// Scratch of parameter_correlations (~43 kB, none of it on the stack): the normal equations,
/// their eliminated target blocks, the scaled matrix and its LDL^T factor (of the 33 rigid
/// parameters, or of all 37 with compliance terms).
struct CorrelationScratch {
  NormalEquations equations;                   ///< J^T W J at the result [m^2/unit^2]
  TargetBlock target_blocks[kMaxTargets - 1];  ///< targets 2.. eliminated as in LM
  NormalMatrix scaled;                         ///< unit-diagonal J^T W J [-]
  Eigen::LDLT<Eigen::Matrix<double, kRigidParamCount, kRigidParamCount>> rigid_factor;  ///< of the 33 [-]
  Eigen::LDLT<NormalMatrix> full_factor;                                                ///< of all 37 [-]
};

/// The correlation matrix of the parameters in `kept` (LmResult::identifiability.kept_mask)
/// at `model` / `base_to_tracker`, from the normal equations of `samples` under `loss` (the
/// ones LM's sigmas come from): rho_ij = C_ij / sqrt(C_ii C_jj), C = (J^T W J)^-1 over the
/// kept parameters. A rigid model (no compliance terms) inverts only the 33 rigid parameters.
/// Entries of parameters not kept are 0. Errors: dataset_empty, non_finite_input,
/// singular_system (the kept parameters' matrix is not positive definite).
Status parameter_correlations(const RobotModel& model, const RigidTransform& base_to_tracker,
                              Span<const Sample> samples, const PointLoss& loss, ParamMask kept,
                              CorrelationScratch* scratch, NormalMatrix* correlation);

/// The parameter most correlated with parameter k among the kept ones (k itself excluded),
/// and that correlation [-]. -1 and 0 when none is kept or every correlation is 0.
struct CorrelationPartner {
  int index = -1;            ///< full parameter index of the partner; -1: none
  double correlation = 0.0;  ///< rho between parameter k and the partner [-]
};
CorrelationPartner strongest_correlation(const NormalMatrix& correlation, int k);

}  // namespace hivecal
