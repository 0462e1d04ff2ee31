// The job's check of joint terms beyond the training poses' joint ranges (calibration.hpp,
// BlockedFoldCheck; docs/compliance.md, "Admitted for the workspace"): internal to the job.
#pragma once

#include "hivecal/calibration.hpp"

namespace hivecal::detail {

/// A fit whose blocked folds are predicted: its point, what it estimates and its prior.
struct FoldFit {
  const RobotModel* model = nullptr;     ///< the fit's model
  const RigidTransform* base = nullptr;  ///< its base -> tracker transform
  ParamMask estimated = 0;               ///< the parameters it estimates (the other targets' tool points stay)
  LmPrior prior;                         ///< the job's prior (LM's)
  double variance_m2 = 0.0;              ///< the fit's variance factor, the prior's weight [m^2]
};

/// Each joint's two end folds' held-out errors under a fit.
using FoldErrors = BlockedFoldErrors;

/// The normal equations of `fit` on `samples` under `loss` into *out, with its prior: the
/// pseudo-observations' weights on the diagonal and their pull (weight (p - nominal)) in the
/// gradient, as LM sums them. `columns`: the parameters (kOtherTargetTools: the other targets'
/// tool points eliminated, into out->targets). Errors: those of the normal equations.
Status fit_normal_equations(const FoldFit& fit, Span<const Sample> samples, const PointLoss& loss, ParamMask columns,
                            NormalEquations* out);

/// The blocked folds of `dataset`'s training samples (each joint's lowest and highest
/// kBlockedFoldShare of them) predicted, each by one Gauss-Newton step of `fit` on the other
/// training samples (the normal equations of all minus the fold's, with the prior), into *out.
/// Reorders the training samples while it works and restores the split's order
/// (DatasetBase::restore_split). Uses the workspace's reliability phase. Errors: those of the
/// normal equations (non_finite_input).
Status blocked_fold_errors(DatasetBase* dataset, const FoldFit& fit, const PointLoss& loss,
                           CalibrationWorkspaceBase& workspace, FoldErrors* out);

}  // namespace hivecal::detail
