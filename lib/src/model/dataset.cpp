#include "hivecal/model/dataset.hpp"

#include "hivecal/core/random.hpp"

namespace hivecal {

int target_count(Span<const Sample> samples) {
  int count = 1;
  for (const Sample& sample : samples) count = sample.target + 1 > count ? sample.target + 1 : count;
  return count;
}

Status DatasetBase::add(const JointVector& q_rad, const Vec3& point_m, int target) {
  if (!all_finite(q_rad) || !all_finite(point_m)) return Status::non_finite_input;
  if (target < 0 || target >= kMaxTargets) return Status::invalid_argument;
  if (full()) return Status::dataset_full;
  storage_[size_].q_rad = q_rad;
  storage_[size_].point_m = point_m;
  storage_[size_].target = target;
  ++size_;
  train_count_ = size_;
  return Status::ok;
}

void DatasetBase::clear() {
  size_ = 0;
  train_count_ = 0;
}

std::size_t DatasetBase::train_count_for(double train_fraction) const {
  if (!(train_fraction > 0.0 && train_fraction <= 1.0)) return 0;
  return static_cast<std::size_t>(train_fraction * static_cast<double>(size_) + 0.5);
}

Status DatasetBase::split(double train_fraction, std::uint64_t seed) {
  if (size_ == 0) return Status::dataset_empty;
  const std::size_t train_count = train_count_for(train_fraction);
  if (train_count == 0) return Status::invalid_argument;
  Random random(seed);
  for (std::size_t i = size_ - 1; i > 0; --i) {
    const auto j = static_cast<std::size_t>(random.below(static_cast<std::uint64_t>(i) + 1U));
    const Sample tmp = storage_[i];
    storage_[i] = storage_[j];
    storage_[j] = tmp;
  }
  train_count_ = train_count;
  return Status::ok;
}

}  // namespace hivecal
