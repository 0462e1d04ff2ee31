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
struct FoldErrors {
  double sum_m[kJointCount][2] = {};       ///< sum of the 3-D errors of the fold's samples [m]
  double squares_m2[kJointCount][2] = {};  ///< sum of their squares [m^2]
  std::size_t count[kJointCount][2] = {};  ///< samples of the fold [-]
  bool solved[kJointCount][2] = {};        ///< the fit of the others could be made (a positive definite system)
};

/// The harmonic terms of `model` whose joint the training samples turn through less than
/// kHarmonicMinPeriodShare of the term's period.
ParamMask harmonics_short_of_their_period(const RobotModel& model, Span<const Sample> train);

/// The blocked folds of `dataset`'s training samples (each joint's lowest and highest
/// kBlockedFoldShare of them) predicted, each by one Gauss-Newton step of `fit` on the other
/// training samples (the normal equations of all minus the fold's, with the prior), into *out.
/// Reorders the training samples while it works and restores the split's order
/// (DatasetBase::restore_split). Uses the workspace's reliability phase. Errors: those of the
/// normal equations (non_finite_input).
Status blocked_fold_errors(DatasetBase* dataset, const FoldFit& fit, const PointLoss& loss,
                           CalibrationWorkspaceBase& workspace, FoldErrors* out);

}  // namespace hivecal::detail
