// The paper's calibration cost over six lengths (d1, a2, a3, d4, d5, d6 of a UR arm, every
// other parameter held at the given geometry): mean absolute 3D error with the robot base ->
// tracker transform refitted (Kabsch) for each candidate, the same number as
// evaluate_cost(..., CostKind::mean_abs_3d, BaseFrame::refit, ...), but precomputed.
//
// With the joint angles fixed, the tool point is affine in these lengths:
// p_i(L) = p_i(L0) + V_i (L - L0), V_i the Jacobian columns (z_0, x_2, x_3, z_3, z_4, z_5).
// The Kabsch cross-covariance is then affine too, H(L) = H_0 + sum_k (L - L0)_k G_k, so a
// candidate costs one 3x3 rotation fit plus one pass of ~50 flops per sample
// (docs/solvers-abc-gsa.md). Everything is expressed in a reference base frame (the nominal
// fit), where measured and predicted points nearly coincide: their differences are small, so
// the terms keep their accuracy even stored as float (the firmware layout, 84 bytes/sample).
// Terms live in Paper6Cost<Capacity, Scalar>; algorithms take the size-erased Paper6CostBase.
#pragma once

#include <cstddef>
#include <type_traits>

#include "hivecal/model/dataset.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/solve/objective.hpp"
#include "hivecal/core/status.hpp"
#include "hivecal/core/types.hpp"

namespace hivecal {

/// Number of lengths the paper calibrates.
inline constexpr std::size_t kPaper6Dimension = 6;
/// ModelParams indices of the six lengths, in parameter-vector order: d1, a2, a3, d4, d5, d6.
inline constexpr int kPaper6ParamIndex[kPaper6Dimension] = {
    model_param_index(0, DhField::d), model_param_index(1, DhField::a), model_param_index(2, DhField::a),
    model_param_index(3, DhField::d), model_param_index(4, DhField::d), model_param_index(5, DhField::d)};
/// Default half-width of the search box around the nominal lengths [m].
inline constexpr double kPaper6DefaultHalfWidth_m = 2e-3;

/// The six lengths d1, a2, a3, d4, d5, d6 [m].
using Paper6Lengths = Eigen::Matrix<double, static_cast<int>(kPaper6Dimension), 1>;

/// The six lengths of a geometry [m].
Paper6Lengths paper6_lengths(const RobotModel& model);
/// `model` with its six lengths replaced by lengths_m[0..6) [m].
RobotModel with_paper6_lengths(const RobotModel& model, const double* lengths_m);

/// A search box nominal +/- half width for the six lengths, owning its bounds.
struct Paper6Box {
  double lower_m[kPaper6Dimension] = {};  ///< lower bounds [m]
  double upper_m[kPaper6Dimension] = {};  ///< upper bounds [m]
  /// The bounds as the solvers take them (views into this object).
  SearchBox view() const { return SearchBox{Span<const double>(lower_m), Span<const double>(upper_m)}; }
};

/// The box nominal +/- half_width_m around the six lengths of `nominal`.
/// Errors: non_finite_input (NaN/Inf in the lengths), invalid_argument (half width not finite and > 0).
Status paper6_box(const RobotModel& nominal, double half_width_m, Paper6Box* box);

/// Values kept per sample, in a storage precision (docs/solvers-abc-gsa.md, memory):
///  [0, 3)  predicted tool point at the expansion point, minus the first sample's [m];
///  [3, 6)  measured point mapped into the reference base frame, minus the predicted point:
///          the nominal residual, small (sub-mm) when the reference is the nominal fit [m];
///  [6, 21) Jacobian columns of a2..d6 in the base frame, column-major [m/m]; d1's column is
///          the constant base z axis, which the refitted translation absorbs (d1 does not
///          change the cost), so it is not stored.
/// Stored in blocks of kPaper6BlockSamples samples, value-major inside a block (the block's
/// value 0, then its value 1, ...): the per-candidate pass reads each value as a contiguous
/// run at a fixed offset from one pointer, which the compiler turns into SIMD across samples.
inline constexpr std::size_t kPaper6ValuesPerSample = 21;
/// Samples per storage block; capacities are rounded up to a whole number of blocks.
inline constexpr std::size_t kPaper6BlockSamples = 32;
/// Values a cost with room for `capacity` samples stores (whole blocks).
constexpr std::size_t paper6_storage_values(std::size_t capacity) {
  return (capacity + kPaper6BlockSamples - 1) / kPaper6BlockSamples * kPaper6BlockSamples * kPaper6ValuesPerSample;
}

/// The precomputed cost over caller-sized term storage (see Paper6Cost for the owning type).
/// Fill it with build(), or stream samples with reset(), add()... and finalize().
class Paper6CostBase : public Objective {
 public:
  Paper6CostBase(const Paper6CostBase&) = delete;
  Paper6CostBase& operator=(const Paper6CostBase&) = delete;

  /// Forgets every sample and sets the geometry: its six lengths are the expansion point,
  /// everything else (angles, other lengths, tool) stays fixed. `reference_base_to_tracker` is
  /// the frame the terms are kept in: any transform is exact with double terms; float terms
  /// need it within ~1 cm and ~10 mrad of the truth (a previous calibration, or a fit of the
  /// first poses). Errors: non_finite_input.
  Status reset(const RobotModel& nominal, const RigidTransform& reference_base_to_tracker);
  /// Adds one sample (the cost is not usable until finalize()). Errors: non_finite_input,
  /// dataset_full (not stored).
  Status add(const JointVector& q_rad, const Vec3& point_m);
  /// Precomputes the centroids and base-fit matrices (again after more add()s). Errors:
  /// too_few_samples (< 3), degenerate_geometry (measured or predicted points collinear or coincident).
  Status finalize();
  /// Fits the nominal base -> tracker transform as the reference, then reset(), add() of every
  /// sample, finalize(). Errors: dataset_empty, and those of fit_base_to_tracker and the three.
  Status build(const RobotModel& nominal, Span<const Sample> samples);

  /// kPaper6Dimension.
  std::size_t dimension() const override { return kPaper6Dimension; }
  /// MAE [m] at lengths_m[0..6) [m]; NaN when not finalised.
  double evaluate(const double* lengths_m) override { return mean_abs_error(lengths_m, nullptr); }
  /// Checked evaluation: the MAE [m] and, if base_to_tracker is not null, the refitted transform.
  /// Errors: invalid_argument (not finalised), non_finite_input (NaN/Inf lengths or cost).
  Status evaluate(const Paper6Lengths& lengths_m, double* mae_m, RigidTransform* base_to_tracker) const;

  /// The geometry given to reset() (the six lengths at the expansion point).
  const RobotModel& nominal() const { return nominal_; }
  /// The frame the terms are kept in (see reset()).
  const RigidTransform& reference() const { return reference_; }
  /// The nominal geometry with lengths_m[0..6) [m] put in.
  RobotModel model_for(const double* lengths_m) const { return with_paper6_lengths(nominal_, lengths_m); }
  std::size_t size() const { return size_; }          ///< samples added
  std::size_t capacity() const { return capacity_; }  ///< samples it can hold
  bool ready() const { return ready_; }               ///< finalize() succeeded since the last change

 protected:
  /// `values`: paper6_storage_values(capacity) values, exact (double) or compact (float).
  Paper6CostBase(double* values, std::size_t capacity) : values_(values), capacity_(capacity) {}
  Paper6CostBase(float* values, std::size_t capacity) : compact_values_(values), capacity_(capacity) {}
  ~Paper6CostBase() = default;

 private:
  using Directions = Eigen::Matrix<double, 3, static_cast<int>(kPaper6Dimension)>;
  template <typename Scalar>
  void store(const Vec3& predicted_m, const Vec3& measured_m, const ToolPointJacobian& jacobian, Scalar* values) const;
  template <typename Scalar>
  Status precompute(const Scalar* values);
  template <typename Scalar>
  double sum_abs_residuals(const Scalar* values, const Mat3& rotation, const Vec3& shift_m, const double* tail_m) const;
  double mean_abs_error(const double* lengths_m, RigidTransform* base_to_tracker) const;

  double* values_ = nullptr;         // exact layout, or
  float* compact_values_ = nullptr;  // compact layout (blocks, see kPaper6ValuesPerSample)
  std::size_t capacity_;
  std::size_t size_ = 0;
  bool ready_ = false;
  RobotModel nominal_;
  RigidTransform reference_;
  Paper6Lengths nominal_lengths_m_ = Paper6Lengths::Zero();
  Vec3 point_origin_m_ = Vec3::Zero();       // first sample's predicted point [m]
  Vec3 point_mean_m_ = Vec3::Zero();         // predicted centroid at the expansion point, relative [m]
  Vec3 measured_mean_m_ = Vec3::Zero();      // measured centroid in the reference frame, relative [m]
  Directions direction_mean_ = Directions::Zero();  // mean Jacobian columns, all six [m/m]
  Mat3 cross_nominal_m2_ = Mat3::Zero();     // H_0 = sum p_c m_c^T, reference frame [m^2]
  Mat3 cross_per_length_m_[kPaper6Dimension - 1];  // G_k = sum v_c,k m_c^T for a2..d6 [m]
};

/// A precomputed paper-6 cost owning room for `Capacity` samples, no heap: 168 bytes each
/// with Scalar = double (exact), 84 with float (firmware: docs/solvers-abc-gsa.md, memory).
template <std::size_t Capacity, typename Scalar = double>
class Paper6Cost final : public Paper6CostBase {
  static_assert(std::is_same<Scalar, double>::value || std::is_same<Scalar, float>::value, "double or float terms");

 public:
  Paper6Cost() : Paper6CostBase(values_, Capacity) {}

 private:
  // Zero-initialised: the evaluation reads whole pairs of samples, past the last one too.
  Scalar values_[paper6_storage_values(Capacity)] = {};
};

}  // namespace hivecal
