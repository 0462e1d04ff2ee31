// Accuracy figures in the shape of the paper's Table 2: MAE and sigma per axis and 3D.
#pragma once

#include <cstddef>

#include "hivecal/model/dataset.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/core/types.hpp"

namespace hivecal {

/// Which error component a statistic is about.
enum class ErrorAxis : int { x = 0, y = 1, z = 2, norm_3d = 3 };
inline constexpr int kErrorAxisCount = 4;

/// Statistics of e = predicted - measured over a set of samples, per component.
/// For x, y, z the statistics are of |e_axis|; for norm_3d of |e|.
struct ErrorStats {
  std::size_t count = 0;                 ///< samples summarised
  double mae_m[kErrorAxisCount] = {};    ///< mean absolute error [m]
  double sigma_m[kErrorAxisCount] = {};  ///< sample standard deviation of the absolute error [m]
  double max_m[kErrorAxisCount] = {};    ///< largest absolute error [m]

  double mae(ErrorAxis axis) const { return mae_m[static_cast<int>(axis)]; }      ///< [m]
  double sigma(ErrorAxis axis) const { return sigma_m[static_cast<int>(axis)]; }  ///< [m]
  double max(ErrorAxis axis) const { return max_m[static_cast<int>(axis)]; }      ///< [m]
};

/// Train, test and overall statistics of one calibrated model (the paper's Table 2).
struct AccuracyReport {
  ErrorStats train;    ///< on the training samples
  ErrorStats test;     ///< on the held-out samples
  ErrorStats overall;  ///< on all samples
};

/// Error statistics of predictions base_to_tracker * FK(q) * tool against the measured points.
ErrorStats position_error_stats(const RobotModel& model, const RigidTransform& base_to_tracker,
                                Span<const Sample> samples);

/// Statistics on the dataset's train, test and whole parts.
AccuracyReport accuracy_report(const RobotModel& model, const RigidTransform& base_to_tracker,
                               const DatasetBase& dataset);

/// Repeated readings that scatter less than this are identical: rounded by the exporting tool or
/// simulated without noise. No tracker resolves 1 nm, so they say nothing of its noise [m].
inline constexpr double kIdenticalReadingsSigma_m = 1e-9;

/// The measurement noise that repeated readings show: a reflector read more than once at one
/// pose (consecutive samples at equal joints with the same target; a pose as Dataset groups
/// its samples) scatters by the tracker's noise alone, whatever the model's error. Joints
/// that differ at all are not one reading: a robot creeping at a stop moves the point (1e-3 rad
/// is a millimetre at a metre's reach), and that is not the tracker's noise.
struct RepeatedReadingNoise {
  std::size_t groups = 0;    ///< (pose, target) pairs read more than once [-]
  std::size_t readings = 0;  ///< readings in those groups [-]
  /// Pooled standard deviation per axis, sqrt(sum (p - mean)^2 / (readings - groups)) over
  /// each group's readings [m]; 0 when there is no group.
  double sigma_axis_m[3] = {};
  /// The three axes pooled: sqrt(sum |p - mean|^2 / (3 (readings - groups))) [m]; 0 when
  /// there is no group.
  double sigma_m = 0.0;

  /// The readings scatter: they measure the tracker's noise (kIdenticalReadingsSigma_m).
  bool measured() const { return groups > 0 && sigma_m >= kIdenticalReadingsSigma_m; }
};

/// The noise of repeated readings in `samples` (no model involved). A run of consecutive
/// samples at equal joints is one pose; within a run, the samples of each target form a group.
RepeatedReadingNoise repeated_reading_noise(Span<const Sample> samples);

}  // namespace hivecal
