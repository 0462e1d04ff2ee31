// Calibration cost of a candidate geometry over paired samples.
#pragma once

#include "hivecal/dataset.hpp"
#include "hivecal/kinematics.hpp"
#include "hivecal/status.hpp"
#include "hivecal/types.hpp"

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

/// Fits the robot base -> tracker transform that best maps the model's predicted tool
/// points onto the measured ones. Errors: those of RigidFitAccumulator::solve.
Status fit_base_to_tracker(const RobotModel& model, Span<const Sample> samples, RigidTransform* base_to_tracker);

/// Cost of `model` on `samples`. With BaseFrame::refit the fitted transform is written
/// to *base_to_tracker; with BaseFrame::fixed it is read from there.
/// Errors: dataset_empty, non_finite_input (a NaN cost), and fit errors in refit mode.
Status evaluate_cost(const RobotModel& model, Span<const Sample> samples, CostKind kind, BaseFrame base_frame,
                     RigidTransform* base_to_tracker, double* cost);

/// The same for a parameter vector (see to_params / from_params).
Status evaluate_cost(const ModelParams& params, Span<const Sample> samples, CostKind kind, BaseFrame base_frame,
                     RigidTransform* base_to_tracker, double* cost);

}  // namespace hivecal
