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
  int target = 0;                           ///< which reflector was measured, 0-based (< kMaxTargets) [-]
};

/// Number of distinct targets `samples` use: the largest target index + 1 (1 when empty) [-].
int target_count(Span<const Sample> samples);
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
  /// anywhere), invalid_argument (target outside [0, kMaxTargets)), dataset_full (not stored).
  /// Any earlier split is discarded (all samples count as training again).
  Status add(const JointVector& q_rad, const Vec3& point_m, int target = 0);
  /// Removes every sample.
  void clear();

  std::size_t size() const { return size_; }            ///< samples stored
  std::size_t capacity() const { return capacity_; }    ///< samples it can hold
  bool full() const { return size_ == capacity_; }      ///< no room for another sample

  /// All samples, training ones first after split().
  Span<const Sample> samples() const { return Span<const Sample>(storage_, size_); }
  /// Training samples (all of them until split() is called).
  Span<const Sample> train() const { return Span<const Sample>(storage_, train_count_); }
  /// Test samples (none until split() is called).
  Span<const Sample> test() const { return Span<const Sample>(storage_ + train_count_, size_ - train_count_); }

  /// Shuffles the samples with a seeded Fisher-Yates permutation and puts the first
  /// round(train_fraction * size) in the training part. Errors: dataset_empty,
  /// invalid_argument (fraction not in (0, 1] or leaving no training sample).
  Status split(double train_fraction, std::uint64_t seed);
  /// Training samples split(train_fraction, ...) keeps: round(train_fraction * size), or 0 when
  /// the fraction is not in (0, 1] (a caller can check a split before a long job) [-].
  std::size_t train_count_for(double train_fraction) const;

 protected:
  DatasetBase(Sample* storage, std::size_t capacity) : storage_(storage), capacity_(capacity) {}
  ~DatasetBase() = default;

 private:
  Sample* storage_;
  std::size_t capacity_;
  std::size_t size_ = 0;
  std::size_t train_count_ = 0;
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
