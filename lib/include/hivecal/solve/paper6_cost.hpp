// The paper's calibration cost over the link lengths (every d and a that is non-zero in the
// start geometry; for a UR arm the paper's six: d1, a2, a3, d4, d5, d6), every other parameter
// held at the given geometry: mean absolute 3D error with the robot base -> tracker transform
// refitted (Kabsch) for each candidate, the same number as
// evaluate_cost(..., CostKind::mean_abs_3d, BaseFrame::refit, ...), but precomputed.
//
// With the joint angles fixed, the tool point is affine in these lengths:
// p_i(L) = p_i(L0) + V_i (L - L0), V_i the Jacobian columns (for UR z_0, x_2, x_3, z_3, z_4, z_5).
// The Kabsch cross-covariance is then affine too, H(L) = H_0 + sum_k (L - L0)_k G_k, so a
// candidate costs one 3x3 rotation fit plus one pass of ~50 flops per sample
// (docs/solvers-abc-gsa.md). Everything is expressed in a reference base frame (the nominal
// fit), where measured and predicted points nearly coincide: their differences are small, so
// the terms keep their accuracy even stored as float (the firmware layout, 84 bytes/sample).
// Terms live in Paper6Cost<Capacity, Scalar, MaxLengths>; algorithms take the size-erased
// Paper6CostBase.
#pragma once

#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "hivecal/model/dataset.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/solve/objective.hpp"
#include "hivecal/core/status.hpp"
#include "hivecal/core/types.hpp"

namespace hivecal {

/// Number of lengths the paper calibrates (a UR arm's link lengths; the firmware's capacity).
inline constexpr std::size_t kPaper6Dimension = 6;
/// Most link lengths a model can have: every d and a of its joints.
inline constexpr std::size_t kMaxLinkLengths = 2 * static_cast<std::size_t>(kMaxJoints);
/// Default half-width of the search box around the nominal lengths [m].
inline constexpr double kPaper6DefaultHalfWidth_m = 2e-3;

/// Which parameters are the link lengths of an arm.
struct LinkLengthSet {
  std::size_t count = 0;                  ///< number of link lengths K [-]
  int param_index[kMaxLinkLengths] = {};  ///< their ModelParams indices, ascending [-]
  /// Whether d1 is one of them (it slides every point along the base z axis alike).
  bool has_d1() const { return count > 0 && param_index[0] == model_param_index(0, DhField::d); }
};

/// Every d and a that is non-zero in `nominal`, in parameter-vector order (for a UR arm the
/// paper's six: d1, a2, a3, d4, d5, d6).
LinkLengthSet link_length_set(const RobotModel& nominal);

/// The link lengths of one arm: the first `count` entries of `values_m`, zeros after them
/// (fixed capacity kMaxLinkLengths; the count is the arm's: 5 for an IRB120, 6 for UR).
struct LinkLengths {
  /// Room for every d and a of the joints [m].
  using Values = Eigen::Matrix<double, static_cast<int>(kMaxLinkLengths), 1>;
  std::size_t count = 0;             ///< number of lengths K [-]
  Values values_m = Values::Zero();  ///< the lengths in [0, count), zero after [m]
  /// The lengths as an array [m] (what with_link_lengths and the solvers take).
  const double* data() const { return values_m.data(); }
  /// The lengths as an array, for writing [m].
  double* data() { return values_m.data(); }
};

/// The lengths of `set` in `model` [m].
LinkLengths link_lengths(const RobotModel& model, const LinkLengthSet& set);
/// The lengths of `model`'s own link-length set [m] (link_length_set(model)).
LinkLengths link_lengths(const RobotModel& model);
/// `model` with the lengths of `set` replaced by lengths_m[0..set.count) [m].
RobotModel with_link_lengths(const RobotModel& model, const LinkLengthSet& set, const double* lengths_m);

/// A search box nominal +/- half width for the link lengths, owning its bounds.
struct LinkLengthBox {
  std::size_t count = 0;                 ///< number of lengths [-]
  double lower_m[kMaxLinkLengths] = {};  ///< lower bounds [m]
  double upper_m[kMaxLinkLengths] = {};  ///< upper bounds [m]
  /// The bounds as the solvers take them (views into this object).
  SearchBox view() const { return SearchBox{Span<const double>(lower_m, count), Span<const double>(upper_m, count)}; }
};

/// The box nominal +/- half_width_m around the link lengths of `nominal`.
/// Errors: non_finite_input (NaN/Inf in the lengths), invalid_argument (half width not finite
/// and > 0, or no link length).
Status link_length_box(const RobotModel& nominal, double half_width_m, LinkLengthBox* box);

/// Values kept per sample, in a storage precision (docs/solvers-abc-gsa.md, memory):
///  [0, 3)  predicted tool point at the expansion point, minus the first sample's [m];
///  [3, 6)  measured point mapped into the reference base frame, minus the predicted point:
///          the nominal residual, small (sub-mm) when the reference is the nominal fit [m];
///  [6, ..) Jacobian columns of the lengths other than d1 in the base frame, column-major
///          [m/m] (for UR a2..d6: 21 values); d1's column is the constant base z axis, which
///          the refitted translation absorbs (d1 does not change the cost), so it is not stored.
/// Stored in blocks of kPaper6BlockSamples samples, value-major inside a block (the block's
/// value 0, then its value 1, ...): the per-candidate pass reads each value as a contiguous
/// run at a fixed offset from one pointer, which the compiler turns into SIMD across samples.
/// For the paper's six lengths (d1 and five stored columns): 21.
inline constexpr std::size_t kPaper6ValuesPerSample = 21;
/// Values per sample of `lengths` link lengths at most: 3 + 3 K (d1 not stored; without d1
/// one length fewer fits).
constexpr std::size_t link_length_values_per_sample(std::size_t lengths) {
  return 3 + 3 * lengths;
}
/// Samples per storage block; capacities are rounded up to a whole number of blocks.
inline constexpr std::size_t kPaper6BlockSamples = 32;
/// Values a cost with room for `capacity` samples stores (whole blocks).
/// Values a cost with room for `capacity` samples of up to `max_lengths` lengths stores (whole blocks).
constexpr std::size_t paper6_storage_values(std::size_t capacity, std::size_t max_lengths = kPaper6Dimension) {
  return (capacity + kPaper6BlockSamples - 1) / kPaper6BlockSamples * kPaper6BlockSamples *
         link_length_values_per_sample(max_lengths);
}

/// The precomputed cost over caller-sized term storage (see Paper6Cost for the owning type).
/// Fill it with build(), or stream samples with reset(), add()... and finalize().
class Paper6CostBase : public Objective {
 public:
  Paper6CostBase(const Paper6CostBase&) = delete;
  Paper6CostBase& operator=(const Paper6CostBase&) = delete;

  /// Forgets every sample and sets the geometry: its link lengths (link_length_set) are the
  /// expansion point, everything else (angles, zero lengths, tool) stays fixed.
  /// `reference_base_to_tracker` is the frame the terms are kept in: any transform is exact
  /// with double terms; float terms need it within ~1 cm and ~10 mrad of the truth (a previous
  /// calibration, or a fit of the first poses). Errors: non_finite_input,
  /// dimension_out_of_range (no link length, or more than the storage holds).
  Status reset(const RobotModel& nominal, const RigidTransform& reference_base_to_tracker);
  /// Adds one sample of target `target` (0-based; its tool point from the geometry of reset(),
  /// fixed) (the cost is not usable until finalize()). Errors: non_finite_input,
  /// invalid_argument (target outside [0, kMaxTargets)), dataset_full (not stored).
  Status add(const JointVector& q_rad, const Vec3& point_m, int target = 0);
  /// Precomputes the centroids and base-fit matrices (again after more add()s). Errors:
  /// too_few_samples (< 3), degenerate_geometry (measured or predicted points collinear or coincident).
  Status finalize();
  /// Fits the nominal base -> tracker transform as the reference, then reset(), add() of every
  /// sample, finalize(). Errors: dataset_empty, and those of fit_base_to_tracker and the three.
  Status build(const RobotModel& nominal, Span<const Sample> samples);
  /// The same with only the samples at positions `selection` (ascending; empty: all) added;
  /// the reference is still fitted on every sample. Errors: those of build(), and
  /// invalid_argument (a position outside `samples`).
  Status build(const RobotModel& nominal, Span<const Sample> samples, Span<const std::uint32_t> selection);

  /// Number of link lengths K of the geometry given to reset().
  std::size_t dimension() const override { return set_.count; }
  /// MAE [m] at lengths_m[0..K) [m]; NaN when not finalised.
  double evaluate(const double* lengths_m) override { return scalar_.mean_abs_error(*this, lengths_m, nullptr); }
  /// Checked evaluation: the MAE [m] and, if base_to_tracker is not null, the refitted transform.
  /// Errors: invalid_argument (not finalised, or not K lengths), non_finite_input (NaN/Inf
  /// lengths or cost).
  Status evaluate(const LinkLengths& lengths_m, double* mae_m, RigidTransform* base_to_tracker) const;

  /// The geometry given to reset() (the link lengths at the expansion point).
  const RobotModel& nominal() const { return nominal_; }
  /// Its link lengths (which parameters the cost moves).
  const LinkLengthSet& lengths() const { return set_; }
  /// The frame the terms are kept in (see reset()).
  const RigidTransform& reference() const { return reference_; }
  /// The nominal geometry with lengths_m[0..K) [m] put in.
  RobotModel model_for(const double* lengths_m) const { return with_link_lengths(nominal_, set_, lengths_m); }
  std::size_t size() const { return size_; }          ///< samples added
  std::size_t capacity() const { return capacity_; }  ///< samples it can hold
  bool ready() const { return ready_; }               ///< finalize() succeeded since the last change

 protected:
  /// `values`: paper6_storage_values(capacity, max_lengths) values, exact (double) or compact (float).
  Paper6CostBase(double* values, std::size_t capacity, std::size_t max_lengths)
      : values_(values),
        scalar_(ScalarOps{&store_on<double>, &precompute_on<double>, &mean_abs_error_on<double>}),
        capacity_(capacity),
        max_values_per_sample_(link_length_values_per_sample(max_lengths)) {}
  Paper6CostBase(float* values, std::size_t capacity, std::size_t max_lengths)
      : compact_values_(values),
        scalar_(ScalarOps{&store_on<float>, &precompute_on<float>, &mean_abs_error_on<float>}),
        capacity_(capacity),
        max_values_per_sample_(link_length_values_per_sample(max_lengths)) {}
  ~Paper6CostBase() = default;

 private:
  using Directions = Eigen::Matrix<double, 3, static_cast<int>(kMaxLinkLengths)>;
  template <typename Scalar>
  void store(const Vec3& predicted_m, const Vec3& measured_m, const ToolPointJacobian& jacobian, Scalar* values) const;
  template <typename Scalar>
  Status precompute(const Scalar* values);
  template <typename Scalar>
  double sum_abs_residuals(const Scalar* values, const Mat3& rotation, const Vec3& shift_m, const double* tail_m) const;
  template <typename Scalar>
  double mean_abs_error(const Scalar* values, const double* lengths_m, RigidTransform* base_to_tracker) const;
  // store, precompute and mean_abs_error on the storage of scalar Scalar.
  template <typename Scalar>
  static void store_on(Paper6CostBase& cost, const Vec3& predicted_m, const Vec3& measured_m,
                       const ToolPointJacobian& jacobian);
  template <typename Scalar>
  static Status precompute_on(Paper6CostBase& cost);
  template <typename Scalar>
  static double mean_abs_error_on(const Paper6CostBase& cost, const double* lengths_m, RigidTransform* base_to_tracker);
  /// What depends on the storage's scalar, chosen by the constructor: an image whose costs
  /// store one scalar links that scalar's code only (~3 kB each on the firmware).
  struct ScalarOps {
    void (*store)(Paper6CostBase&, const Vec3&, const Vec3&, const ToolPointJacobian&);
    Status (*precompute)(Paper6CostBase&);
    double (*mean_abs_error)(const Paper6CostBase&, const double*, RigidTransform*);
  };

  double* values_ = nullptr;         // exact layout, or
  float* compact_values_ = nullptr;  // compact layout (blocks, see kPaper6ValuesPerSample)
  ScalarOps scalar_;
  std::size_t capacity_;
  std::size_t max_values_per_sample_;                       // what the storage holds per sample
  std::size_t values_per_sample_ = kPaper6ValuesPerSample;  // what the geometry needs: 6 + 3 x stored columns
  std::size_t stored_count_ = 0;                            // lengths with a stored column (all but d1)
  std::size_t size_ = 0;
  LinkLengthSet set_;
  bool ready_ = false;
  RobotModel nominal_;
  RigidTransform reference_;
  double nominal_lengths_m_[kMaxLinkLengths] = {};
  Vec3 point_origin_m_ = Vec3::Zero();              // first sample's predicted point [m]
  Vec3 point_mean_m_ = Vec3::Zero();                // predicted centroid at the expansion point, relative [m]
  Vec3 measured_mean_m_ = Vec3::Zero();             // measured centroid in the reference frame, relative [m]
  Directions direction_mean_ = Directions::Zero();  // mean Jacobian columns, all K [m/m]
  Mat3 cross_nominal_m2_ = Mat3::Zero();            // H_0 = sum p_c m_c^T, reference frame [m^2]
  Mat3 cross_per_length_m_[kMaxLinkLengths] = {};   // G_k = sum v_c,k m_c^T for the stored columns [m]
};

/// Samples a storage of `values` values holds for up to `max_lengths` lengths (whole blocks).
constexpr std::size_t paper6_capacity_of(std::size_t values, std::size_t max_lengths) {
  return values / (kPaper6BlockSamples * link_length_values_per_sample(max_lengths)) * kPaper6BlockSamples;
}

/// A precomputed link-length cost over the caller's storage of exact (double) terms, sized at
/// run time: room for paper6_capacity_of(values.size(), max_lengths) samples of up to
/// `max_lengths` (<= kMaxLinkLengths) lengths. The storage must outlive it; it is zeroed here
/// (the evaluation reads whole blocks, past the last sample too).
class Paper6CostView final : public Paper6CostBase {
 public:
  Paper6CostView(Span<double> values, std::size_t max_lengths);
};

/// A precomputed link-length cost owning room for `Capacity` samples of up to `MaxLengths`
/// lengths, no heap: for the paper's six 168 bytes each with Scalar = double (exact), 84 with
/// float (firmware: docs/solvers-abc-gsa.md, memory); (3 + 3 MaxLengths) values in general.
template <std::size_t Capacity, typename Scalar = double, std::size_t MaxLengths = kPaper6Dimension>
class Paper6Cost final : public Paper6CostBase {
  static_assert(std::is_same<Scalar, double>::value || std::is_same<Scalar, float>::value, "double or float terms");
  static_assert(MaxLengths >= 1 && MaxLengths <= kMaxLinkLengths, "1..kMaxLinkLengths lengths");

 public:
  Paper6Cost() : Paper6CostBase(values_, Capacity, MaxLengths) {}

 private:
  // Zero-initialised: the evaluation reads whole pairs of samples, past the last one too.
  Scalar values_[paper6_storage_values(Capacity, MaxLengths)] = {};
};

}  // namespace hivecal
