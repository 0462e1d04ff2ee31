// Fixed-capacity set of paired samples (joint angles, tracker point) with a seeded
// train/test split. Storage lives in Dataset<Capacity>; every API takes the
// size-erased DatasetBase so it need not know the capacity (the ETL pattern).
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/core/status.hpp"
#include "hivecal/core/types.hpp"
#include "hivecal/model/kinematics.hpp"

namespace hivecal {

/// Default dataset capacity (samples); the paper's sessions hold a few hundred.
inline constexpr std::size_t kDefaultDatasetCapacity = 1024;
/// Default share of samples used for training (the paper's 70/30).
inline constexpr double kDefaultTrainFraction = 0.7;

/// One quasi-static pose: where the joints were and where the tracker saw the tool.
struct Sample {
  JointVector q_rad = JointVector::Zero();  ///< joint positions [rad]
  Vec3 point_m = Vec3::Zero();              ///< measured tool point in the tracker frame [m]
  std::uint32_t index = 0;                  ///< position in the order of add() (maps to the caller's source row) [-]
  int target = 0;                           ///< which reflector was measured, 0-based (< kMaxTargets) [-]
};

/// Number of distinct targets `samples` use: the largest target index + 1 (1 when empty) [-].
int target_count(Span<const Sample> samples);
/// True when no sample has a reading beyond the first `joint_count` joints (they are 0): the
/// samples can be of a model of that many joints.
bool readings_fit_joint_count(Span<const Sample> samples, int joint_count);
/// Joints that agree this closely are one robot pose: the samples of one stop of the robot
/// (encoder noise is ~1e-5 rad; two poses a user plans differ by degrees) [rad].
inline constexpr double kSamePoseTolerance_rad = 1e-3;
/// Joints that agree this closely are one configuration of the arm for what the poses can
/// determine: a robot creeping at a stop, a pose measured twice (a calibration's planned poses
/// differ by degrees to tens of degrees; ~1 degree) [rad].
inline constexpr double kSameConfigurationTolerance_rad = 0.0175;
/// distinct_points() and distinct_configurations() count up to this many, then stop (more is plenty for any model).
inline constexpr std::size_t kDistinctPointLimit = 64;

/// Whether two samples were taken at one robot pose: joints within kSamePoseTolerance_rad
/// (one stop of the robot; any targets).
inline bool same_pose(const Sample& a, const Sample& b) {
  return (a.q_rad - b.q_rad).cwiseAbs().maxCoeff() <= kSamePoseTolerance_rad;
}

/// Whether two samples measure one point: the same target at one pose (same_pose).
inline bool same_point(const Sample& a, const Sample& b) {
  return a.target == b.target && same_pose(a, b);
}

/// Distinct measured points of `samples`: one per robot pose (joints within
/// kSamePoseTolerance_rad) and target, each worth 3 coordinates whatever its sample count;
/// at most kDistinctPointLimit. Many samples of one stop determine no more than one.
std::size_t distinct_points(Span<const Sample> samples);
/// Distinct configurations of the arm in `samples` (joints more than kSameConfigurationTolerance_rad
/// apart; any targets, any repeated readings), at most kDistinctPointLimit.
std::size_t distinct_configurations(Span<const Sample> samples);

/// End of the pose that starts at `begin`: the run of consecutive samples at joints equal to
/// samples[begin]'s (its reflectors, its repeated readings) [-].
std::size_t pose_run_end(Span<const Sample> samples, std::size_t begin);

/// Point of `sample`'s target predicted by `model` in the robot base frame [m].
inline Vec3 fk_sample_point(const RobotModel& model, const Sample& sample) {
  return fk_target_point(model, sample.q_rad, sample.target);
}

/// Capacity-erased dataset: the view every algorithm works on.
class DatasetBase {
 public:
  DatasetBase(const DatasetBase&) = delete;
  DatasetBase& operator=(const DatasetBase&) = delete;

  /// Appends a sample of target `target` (0-based). Errors: non_finite_input (NaN/Inf
  /// anywhere), invalid_argument (target outside [0, kMaxTargets)), dataset_full (not stored:
  /// no room, or 2^29 - 1 samples already, the most a split can number).
  /// Any earlier split is discarded (all samples count as training again).
  Status add(const JointVector& q_rad, const Vec3& point_m, int target = 0);
  /// Removes every sample.
  void clear();

  /// Puts the samples back in the order of add(), then moves those whose Sample::index is in
  /// `indices` (any order, unknown ones ignored) behind the others, keeping both groups in that
  /// order: size(), samples(), train() and test() then cover the kept ones only (as if the
  /// others had never been added) and set_aside() lists the rest. An empty list restores every
  /// sample. Any earlier split is discarded.
  void set_aside(Span<const std::uint32_t> indices);
  /// Exchanges the samples at positions a and b of samples() (a temporary reordering, as
  /// leave-one-out does; swap back to restore). Out-of-range positions are ignored.
  void swap_samples(std::size_t a, std::size_t b);
  /// The samples set aside by set_aside(), in the order of add().
  Span<const Sample> set_aside() const { return Span<const Sample>(storage_ + size_, stored_ - size_); }
  /// Fold `fold` of `folds` for cross-validation: the kept samples in the order of add(),
  /// shuffled as split() does with `seed`, then fold k is the contiguous block of poses
  /// [k P / folds, (k + 1) P / folds) of that order (P = pose_count()), moved behind the rest:
  /// train() is the other folds, test() this one. Errors: dataset_empty, invalid_argument
  /// (folds < 2, folds > pose_count(), fold >= folds).
  Status split_fold(std::size_t fold, std::size_t folds, std::uint64_t seed);
  /// Poses that split() and split_fold() keep together: a run of consecutive samples at equal
  /// joints in the order of add() (the reflectors measured at one pose, the tracker's repeated
  /// readings of one stop), so that no pose is in the training and the test part at once; a
  /// set without such runs has one pose per sample [-].
  std::size_t pose_count() const;

  std::size_t size() const { return size_; }          ///< samples stored and not set aside
  std::size_t capacity() const { return capacity_; }  ///< samples it can hold
  bool full() const { return stored_ == capacity_; }  ///< no room for another sample

  /// All samples, training ones first after split().
  Span<const Sample> samples() const { return Span<const Sample>(storage_, size_); }
  /// Training samples (all of them until split() is called).
  Span<const Sample> train() const { return Span<const Sample>(storage_, train_count_); }
  /// Test samples (none until split() is called).
  Span<const Sample> test() const { return Span<const Sample>(storage_ + train_count_, size_ - train_count_); }

  /// Shuffles the samples with a seeded Fisher-Yates permutation and puts the first
  /// round(train_fraction * size) in the training part; when a pose holds several samples
  /// (pose_count() < size) and there is a test part, the poses are shuffled whole, from the order of add(), and the
  /// training part ends at the pose boundary nearest round(train_fraction * size) samples (at
  /// least min(3, train_count_for(train_fraction)) poses, at least one pose for the test).
  /// Errors: dataset_empty, invalid_argument (fraction not in (0, 1] or leaving no training sample).
  Status split(double train_fraction, std::uint64_t seed);
  /// Puts the kept samples back in the order the last split() or split_fold() made (a
  /// function of the kept samples and its arguments: made again), or, without one since the
  /// last add(), set_aside() or clear(), in the order of add(): for a caller that reordered
  /// them with swap_samples() and cannot undo each swap. Returns that call's status.
  Status restore_split();
  /// Nominal training poses of split(train_fraction, ...): round(train_fraction * pose_count()), or
  /// 0 when the fraction is not in (0, 1]; the split keeps at least min(3, this) (a caller can
  /// check a split before a long job) [-].
  std::size_t train_count_for(double train_fraction) const;

 protected:
  DatasetBase(Sample* storage, std::size_t capacity) : storage_(storage), capacity_(capacity) {}
  ~DatasetBase() = default;
  /// Called by add() when the storage is full: a dataset that can grow (a host program's, over
  /// storage it allocates) gives room for at least `needed` samples through move_to() and
  /// returns true; the library's own fixed-capacity datasets cannot (false: dataset_full).
  virtual bool grow(std::size_t needed) {
    (void)needed;
    return false;
  }
  /// Copies every stored sample (set-aside ones included) to `storage` of `capacity` samples
  /// and works there from now on; false (nothing changed) when they do not fit. Spans taken
  /// before view the old storage.
  bool move_to(Sample* storage, std::size_t capacity);

 private:
  Sample* storage_;
  std::size_t capacity_;
  std::size_t size_ = 0;    // kept samples (the set-aside ones follow them)
  std::size_t stored_ = 0;  // kept + set aside
  std::size_t train_count_ = 0;
  /// The last split's arguments, for restore_split(): kind 0 none, 1 split(), 2 split_fold().
  struct SplitArguments {
    int kind = 0;
    double train_fraction = 0.0;
    std::size_t fold = 0;
    std::size_t folds = 0;
    std::uint64_t seed = 0;
  } last_split_;

  void sort_by_index(std::size_t count);  // the first `count` samples in the order of add()
  void shuffle(std::uint64_t seed);
  std::size_t pose_end(std::size_t begin) const;   // end of the run of equal joints at begin
  std::size_t pose_start(std::size_t pose) const;  // first sample of run `pose` in the current order
  static std::size_t train_poses_of(double train_fraction, std::size_t poses);  // see train_count_for
  // split()'s training samples after shuffle_poses: whole poses nearest the fraction of the samples
  std::size_t train_count_of_poses(double train_fraction, std::size_t train_poses) const;
  void shuffle_poses(std::uint64_t seed);  // add() order, then the runs shuffled whole
};

/// A dataset over storage of the caller's (`capacity` samples at `storage`, which must
/// outlive it), no heap: a size chosen at run time.
class DatasetView final : public DatasetBase {
 public:
  /// Empty, with room for storage.size() samples.
  explicit DatasetView(Span<Sample> storage) : DatasetBase(storage.data(), storage.size()) {}
};

/// A dataset that owns storage for `Capacity` samples (80 bytes each), no heap.
template <std::size_t Capacity = kDefaultDatasetCapacity>
class Dataset final : public DatasetBase {
 public:
  Dataset() : DatasetBase(storage_, Capacity) {}

 private:
  Sample storage_[Capacity];
};

}  // namespace hivecal
