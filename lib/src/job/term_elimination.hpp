// The joint-term test's refits in closed form (internal to the job): the significance test
// fixes one term at a time and fits again; on the linearised fit each fix is a Schur complement
// of its normal equations (docs/compliance.md, "Significance").
#pragma once

#include "hivecal/calibration.hpp"
#include "job/blocked_folds.hpp"

namespace hivecal::detail {

/// The joint terms the significance test goes on to fix after `first` (which it fixes, on the
/// fit's own sigmas), one at a time as it would with a refit after each: a coefficient beyond
/// kMaxJointTermCoefficient first, then the term least significant below its level
/// (parameter_significance_level of `reference` with `significance_t`, `compliance_t` and the
/// residual degrees of freedom, one more per fix). Each fix moves the other estimates, their
/// covariance and the residual sum as the linearised fit (`fit`'s normal equations on `samples`
/// under `loss`, with its prior) does; `sigma_m` and `dof` are the fit's residual sigma and
/// degrees of freedom. Returns `first` with the terms that follow it. Uses the workspace's
/// reliability phase. Errors: those of the normal equations; singular_system.
Status linearised_term_fixes(const FoldFit& fit, const RobotModel& reference, Span<const Sample> samples,
                             const PointLoss& loss, int first, double significance_t, double compliance_t,
                             double sigma_m, int dof, CalibrationWorkspaceBase& workspace, ParamMask* fixed);

}  // namespace hivecal::detail
