// Least-squares rigid transform between paired point sets (Kabsch / Umeyama without
// scale), weighted or not, with the reflection guard and a degeneracy check; and its use
// on a robot model: the robot base -> tracker fit of predicted onto measured tool points.
#pragma once

#include <cstddef>

#include "hivecal/core/status.hpp"
#include "hivecal/core/types.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/model/kinematics.hpp"

namespace hivecal {

/// Relative size of the second principal spread below which points count as collinear.
inline constexpr double kCollinearityThreshold = 1e-10;

/// Streams point pairs in and solves target ~ rotation * source + translation.
/// Memory is constant: sums are kept relative to the first pair for numerical safety.
class RigidFitAccumulator {
 public:
  /// Adds one pair with a weight >= 0; NaN/Inf or a negative weight is remembered and reported by solve().
  void add(const Vec3& source_m, const Vec3& target_m, double weight = 1.0);
  /// Number of pairs with positive weight added so far.
  std::size_t count() const { return count_; }
  /// Forgets every pair.
  void reset() { *this = RigidFitAccumulator(); }
  /// The best rigid transform. Errors: non_finite_input, invalid_argument (bad weight),
  /// too_few_samples (< 3 weighted pairs), degenerate_geometry (collinear or coincident points).
  Status solve(RigidTransform* source_to_target) const;

 private:
  Vec3 source_origin_m_ = Vec3::Zero();
  Vec3 target_origin_m_ = Vec3::Zero();
  double weight_sum_ = 0.0;
  Vec3 source_sum_m_ = Vec3::Zero();
  Vec3 target_sum_m_ = Vec3::Zero();
  Mat3 cross_sum_m2_ = Mat3::Zero();      // sum w s t^T (shifted)
  Mat3 source_moment_m2_ = Mat3::Zero();  // sum w s s^T (shifted)
  Mat3 target_moment_m2_ = Mat3::Zero();  // sum w t t^T (shifted)
  std::size_t count_ = 0;
  bool saw_non_finite_ = false;
  bool saw_bad_weight_ = false;
};

/// The proper rotation R maximising trace(R^T cross_covariance) for
/// cross_covariance = sum (s - s_mean)(t - t_mean)^T, i.e. t ~ R s; the determinant
/// sign is forced to +1 (reflection guard). Solvers with their own moments call this.
Mat3 rotation_from_cross_covariance(const Mat3& cross_covariance);

/// The same rotation as rotation_from_cross_covariance (agreeing to ~1e-15), about 6x faster:
/// Horn's unit quaternion, the eigenvector of the 4x4 key matrix for its largest eigenvalue,
/// which Newton's method finds on the characteristic quartic (Theobald's QCP idea). Falls back
/// to the SVD when that eigenvalue is (nearly) repeated, where the rotation is ill-determined.
Mat3 rotation_from_cross_covariance_qcp(const Mat3& cross_covariance);

/// True when a 3x3 scatter matrix spans at least a plane (see kCollinearityThreshold).
bool scatter_spans_plane(const Mat3& scatter);

/// One-shot fit over paired arrays; `weights` empty for an unweighted fit, else same size.
Status fit_rigid_transform(Span<const Vec3> source_m, Span<const Vec3> target_m, Span<const double> weights,
                           RigidTransform* source_to_target);

/// Fits the robot base -> tracker transform that best maps the model's predicted tool
/// points onto the measured ones. Errors: those of RigidFitAccumulator::solve.
Status fit_base_to_tracker(const RobotModel& model, Span<const Sample> samples, RigidTransform* base_to_tracker);

/// Sets the tool point of every target 2.. that has samples to its least-squares value for
/// the model's joints and `base_to_tracker`: the mean of the measured points in the flange
/// frame (closed form, the flange rotation being orthonormal). Target 1 and targets without
/// samples keep their values.
void fit_other_target_tools(const RigidTransform& base_to_tracker, Span<const Sample> samples, RobotModel* model);

/// fit_base_to_tracker, and with samples of several targets also their tool points 2..:
/// alternated a few rounds (target 1's tool point anchors the base), tools fitted last.
/// With one target exactly fit_base_to_tracker. Errors: those of fit_base_to_tracker.
Status fit_base_and_target_tools(Span<const Sample> samples, RobotModel* model, RigidTransform* base_to_tracker);

}  // namespace hivecal
