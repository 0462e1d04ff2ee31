// Reference calibration cost of a candidate geometry over paired samples: the plain loop
// that the fast costs (paper6_cost.hpp, normal_equations.hpp) are checked against.
#pragma once

#include "hivecal/model/dataset.hpp"
#include "hivecal/model/rigid_fit.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/core/status.hpp"
#include "hivecal/core/types.hpp"

namespace hivecal {

/// How residuals r_i = base_to_tracker * FK(q_i) * tool - point_i are summed.
enum class CostKind : int {
  mean_abs_3d,  ///< mean of |r_i| [m] (the paper's cost)
  sum_squares,  ///< sum of |r_i|^2 [m^2] (least squares)
};

/// Whether the base-to-tracker transform is an input or is refitted for each candidate.
enum class BaseFrame : int {
  fixed,  ///< use the given transform as is
  refit,  ///< fit it to the candidate's predicted points first (Kabsch), then evaluate
};

/// Cost of `model` on `samples`. With BaseFrame::refit the fitted transform is written
/// to *base_to_tracker; with BaseFrame::fixed it is read from there.
/// Errors: invalid_argument (a null pointer), dataset_empty, non_finite_input (a NaN cost), and fit
/// errors in refit mode.
Status evaluate_cost(const RobotModel& model, Span<const Sample> samples, CostKind kind, BaseFrame base_frame,
                     RigidTransform* base_to_tracker, double* cost);

}  // namespace hivecal
