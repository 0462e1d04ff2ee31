#include "hivecal/model/dataset.hpp"

#include "hivecal/core/random.hpp"

namespace hivecal {

bool readings_fit_joint_count(Span<const Sample> samples, int joint_count) {
  for (const Sample& sample : samples) {
    for (int j = joint_count; j < kMaxJoints; ++j) {
      if (sample.q_rad(j) != 0.0) return false;
    }
  }
  return true;
}

int target_count(Span<const Sample> samples) {
  int count = 1;
  for (const Sample& sample : samples) count = sample.target + 1 > count ? sample.target + 1 : count;
  return count;
}

namespace {

// While shuffle_poses runs, each sample carries its pose's new slot in the bits of
// Sample::target above the target itself: the dataset has no memory but its samples, and the
// library allocates none. Outside shuffle_poses those bits are 0.
constexpr int kTargetBits = 2;
static_assert(kMaxTargets <= (1 << kTargetBits), "the targets fit below the slot bits");
/// Poses shuffle_poses can number: slot + 1 above kTargetBits stays a positive int.
constexpr std::size_t kMaxShuffledPoses = (std::size_t{1} << (31 - kTargetBits)) - 1;

/// Whether two samples are at one configuration of the arm (kSameConfigurationTolerance_rad).
bool same_configuration(const Sample& a, const Sample& b) {
  return (a.q_rad - b.q_rad).cwiseAbs().maxCoeff() <= kSameConfigurationTolerance_rad;
}

/// Classes of `samples` under `same`, each stood for by its first sample (a tolerance is not
/// transitive: a sample joins the latest class whose first sample it matches), counted up to
/// kDistinctPointLimit. One loop for every relation (a function pointer, not a template: the
/// firmware's flash holds one copy).
std::size_t count_distinct(Span<const Sample> samples, bool (*same)(const Sample&, const Sample&)) {
  std::size_t first[kDistinctPointLimit];  // a sample of each class found
  std::size_t count = 0;
  for (std::size_t i = 0; i < samples.size() && count < kDistinctPointLimit; ++i) {
    bool seen = false;
    for (std::size_t k = count; k-- > 0 && !seen;) {  // the latest first: a stop's samples are in a row
      seen = same(samples[first[k]], samples[i]);
    }
    if (!seen) first[count++] = i;
  }
  return count;
}

}  // namespace

std::size_t distinct_points(Span<const Sample> samples) {
  return count_distinct(samples, same_point);
}

std::size_t distinct_configurations(Span<const Sample> samples) {
  return count_distinct(samples, same_configuration);
}

bool DatasetBase::move_to(Sample* storage, std::size_t capacity) {
  if (storage == nullptr || capacity < stored_) return false;
  for (std::size_t i = 0; i < stored_; ++i) storage[i] = storage_[i];
  storage_ = storage;
  capacity_ = capacity;
  return true;
}

Status DatasetBase::add(const JointVector& q_rad, const Vec3& point_m, int target) {
  if (!all_finite(q_rad) || !all_finite(point_m)) return Status::non_finite_input;
  if (target < 0 || target >= kMaxTargets) return Status::invalid_argument;
  // A new sample joins every stored one. The empty Span is a null view (no storage, no heap):
  // set_aside() with it only moves the set-aside samples back in place.
  if (stored_ != size_) set_aside(Span<const std::uint32_t>());
  if (stored_ >= kMaxShuffledPoses) return Status::dataset_full;  // see shuffle_poses
  if (full() && (!grow(stored_ + 1) || full())) return Status::dataset_full;
  storage_[size_].q_rad = q_rad;
  storage_[size_].point_m = point_m;
  storage_[size_].index = static_cast<std::uint32_t>(size_);  // unique: the order of add()
  storage_[size_].target = target;
  ++size_;
  stored_ = size_;
  train_count_ = size_;
  last_split_ = SplitArguments{};
  return Status::ok;
}

void DatasetBase::clear() {
  size_ = 0;
  stored_ = 0;
  train_count_ = 0;
  last_split_ = SplitArguments{};
}

namespace {

/// The order of sort_by_index: the pose's slot while shuffle_poses runs (else 0), then the
/// order of add().
std::uint64_t sort_key(const Sample& s) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(s.target) >> kTargetBits) << 32) | s.index;
}

/// Moves s[root] down the max-heap of s[0, end) ordered by sort_key.
void sift_down(Sample* s, std::size_t root, std::size_t end) {
  const Sample moving = s[root];
  const std::uint64_t moving_key = sort_key(moving);
  for (std::size_t child = 2 * root + 1; child < end; child = 2 * root + 1) {
    if (child + 1 < end && sort_key(s[child + 1]) > sort_key(s[child])) ++child;
    if (sort_key(s[child]) <= moving_key) break;
    s[root] = s[child];
    root = child;
  }
  s[root] = moving;
}

/// Swaps s[a] and s[b]: one copy of the 80-byte exchange in flash.
[[gnu::noinline]] void swap_at(Sample* s, std::size_t a, std::size_t b) {
  const Sample tmp = s[a];
  s[a] = s[b];
  s[b] = tmp;
}

/// Reverses s[begin, end) in place.
void reverse(Sample* s, std::size_t begin, std::size_t end) {
  for (; begin + 1 < end; ++begin, --end) swap_at(s, begin, end - 1);
}

/// Rotates s[begin, end) so that s[middle] comes first, the two parts each in their order.
void rotate(Sample* s, std::size_t begin, std::size_t middle, std::size_t end) {
  reverse(s, begin, middle);
  reverse(s, middle, end);
  reverse(s, begin, end);
}

}  // namespace

void DatasetBase::sort_by_index(std::size_t count) {
  // The indices are unique, so the sorted order is one whatever the algorithm. In place and
  // without heap memory: a check (the order of add() is the common case), else heapsort,
  // n log n (an insertion sort's n^2 / 4 moves took 28 s on 200,000 shuffled samples).
  std::size_t sorted = 1;
  while (sorted < count && sort_key(storage_[sorted - 1]) < sort_key(storage_[sorted])) ++sorted;
  if (sorted >= count) return;
  for (std::size_t root = count / 2; root-- > 0;) sift_down(storage_, root, count);
  for (std::size_t end = count - 1; end > 0; --end) {
    swap_at(storage_, 0, end);
    sift_down(storage_, 0, end);
  }
}

void DatasetBase::set_aside(Span<const std::uint32_t> indices) {
  sort_by_index(stored_);
  std::size_t kept = 0;
  for (std::size_t i = 0; i < stored_; ++i) {
    bool aside = false;
    for (std::uint32_t index : indices) aside = aside || storage_[i].index == index;
    if (aside) continue;
    // Stable partition by rotation: the kept sample moves down over the set-aside block.
    const Sample moving = storage_[i];
    for (std::size_t j = i; j > kept; --j) storage_[j] = storage_[j - 1];
    storage_[kept++] = moving;
  }
  size_ = kept;
  train_count_ = size_;
  last_split_ = SplitArguments{};
}

void DatasetBase::swap_samples(std::size_t a, std::size_t b) {
  if (a >= size_ || b >= size_ || a == b) return;
  swap_at(storage_, a, b);
}

void DatasetBase::shuffle(std::uint64_t seed) {
  Random random(seed);
  for (std::size_t i = size_ - 1; i > 0; --i) {
    const auto j = static_cast<std::size_t>(random.below(static_cast<std::uint64_t>(i) + 1U));
    swap_at(storage_, i, j);
  }
}

std::size_t pose_run_end(Span<const Sample> samples, std::size_t begin) {
  std::size_t end = begin + 1;
  while (end < samples.size() && samples[end].q_rad == samples[begin].q_rad) ++end;
  return end;
}

std::size_t DatasetBase::pose_end(std::size_t begin) const {
  return pose_run_end(samples(), begin);
}

std::size_t DatasetBase::pose_count() const {
  std::size_t count = 0;
  for (std::size_t i = 0; i < size_; i = pose_end(i)) ++count;
  return count;
}

std::size_t DatasetBase::pose_start(std::size_t pose) const {
  std::size_t i = 0;
  for (std::size_t k = 0; k < pose && i < size_; ++k) i = pose_end(i);
  return i;
}

namespace {

/// Where shuffle_poses looks for the k-th pose not placed yet: the poses in blocks of equal
/// counts, each block's first sample and how many of its poses are still to place. A pick
/// walks the counts, then one block (not every pose before it: that was n^2 / 2).
struct PoseDirectory {
  static constexpr std::size_t kBlocks = 256;
  std::uint32_t first_sample[kBlocks];  ///< each block's first sample (add() keeps them below kMaxShuffledPoses)
  std::uint32_t unplaced[kBlocks];      ///< each block's poses not placed yet
};

}  // namespace

void DatasetBase::shuffle_poses(std::uint64_t seed) {
  // Slot p takes a uniformly drawn one of the poses not placed yet, counted in the order of
  // add(). The slots are marked on the samples (sort_key), then one sort moves every pose to
  // its slot, its samples in their order.
  sort_by_index(size_);
  const std::size_t poses = pose_count();  // below kMaxShuffledPoses: add() refuses more samples
  PoseDirectory directory;
  const std::size_t per_block = (poses + PoseDirectory::kBlocks - 1) / PoseDirectory::kBlocks;
  for (std::size_t pose = 0, i = 0; pose < poses; ++pose, i = pose_end(i)) {
    if (pose % per_block == 0) {
      directory.first_sample[pose / per_block] = static_cast<std::uint32_t>(i);
      directory.unplaced[pose / per_block] = 0;
    }
    ++directory.unplaced[pose / per_block];
  }
  Random random(seed);
  for (std::size_t slot = 0; slot < poses; ++slot) {
    const std::size_t remaining = poses - slot;
    auto pick = remaining > 1 ? static_cast<std::size_t>(random.below(static_cast<std::uint64_t>(remaining))) : 0;
    std::size_t block = 0;
    for (; pick >= directory.unplaced[block]; ++block) pick -= directory.unplaced[block];
    std::size_t begin = directory.first_sample[block];
    for (;; begin = pose_end(begin)) {
      if (sort_key(storage_[begin]) >> 32 == 0 && pick-- == 0) break;  // not placed yet
    }
    --directory.unplaced[block];
    const std::size_t end = pose_end(begin);
    const auto mark = static_cast<int>((slot + 1) << kTargetBits);
    for (std::size_t i = begin; i < end; ++i) storage_[i].target |= mark;
  }
  sort_by_index(size_);
  for (std::size_t i = 0; i < size_; ++i) storage_[i].target &= (1 << kTargetBits) - 1;
}

Status DatasetBase::split_fold(std::size_t fold, std::size_t folds, std::uint64_t seed) {
  if (size_ == 0) return Status::dataset_empty;
  const std::size_t poses = pose_count();
  if (folds < 2 || folds > poses || fold >= folds) return Status::invalid_argument;
  sort_by_index(size_);  // the kept samples in the order of add(): the same folds whatever the order before
  if (poses == size_) {
    shuffle(seed);
  } else {
    shuffle_poses(seed);
  }
  const std::size_t begin = pose_start(fold * poses / folds);
  const std::size_t end = pose_start((fold + 1) * poses / folds);
  rotate(storage_, begin, end, size_);  // the fold's block to the end, both parts in their order
  train_count_ = size_ - (end - begin);
  last_split_ = SplitArguments{2, 1.0, fold, folds, seed};
  return Status::ok;
}

Status DatasetBase::restore_split() {
  const SplitArguments last = last_split_;
  sort_by_index(size_);  // split() shuffles the order it finds: the one it found, the order of add()
  if (last.kind == 1) return split(last.train_fraction, last.seed);
  if (last.kind == 2) return split_fold(last.fold, last.folds, last.seed);
  return Status::ok;
}

std::size_t DatasetBase::train_poses_of(double train_fraction, std::size_t poses) {
  if (!(train_fraction > 0.0 && train_fraction <= 1.0)) return 0;
  return static_cast<std::size_t>(train_fraction * static_cast<double>(poses) + 0.5);
}

std::size_t DatasetBase::train_count_for(double train_fraction) const {
  return train_poses_of(train_fraction, pose_count());
}

Status DatasetBase::split(double train_fraction, std::uint64_t seed) {
  if (size_ == 0) return Status::dataset_empty;
  const std::size_t poses = pose_count();
  const std::size_t train_poses = train_poses_of(train_fraction, poses);
  if (train_poses == 0) return Status::invalid_argument;
  last_split_ = SplitArguments{1, train_fraction, 0, 0, seed};
  if (poses == size_ || train_poses == poses) {  // one sample per pose, or no test: the draws as always
    shuffle(seed);
    train_count_ = train_poses == poses ? size_ : train_poses;
    return Status::ok;
  }
  shuffle_poses(seed);
  train_count_ = train_count_of_poses(train_fraction, train_poses);
  return Status::ok;
}

std::size_t DatasetBase::train_count_of_poses(double train_fraction, std::size_t train_poses) const {
  // Poses differ in their sample counts (a stop's repeated readings, a slow approach's single
  // ones): round(train_fraction * poses) poses could hold anywhere from half to nearly all the
  // samples. So the cut is the pose boundary nearest round(train_fraction * size) samples (a tie:
  // the later one), with at least min(3, train_poses) poses (what the tracker frame needs, and
  // what train_count_for promised) and at least one pose for the test.
  const auto target = static_cast<std::size_t>(train_fraction * static_cast<double>(size_) + 0.5);
  const std::size_t least_poses = train_poses < 3 ? train_poses : 3;
  std::size_t best = 0;
  std::size_t end = 0;
  for (std::size_t pose = 1; end < size_; ++pose) {
    end = pose_end(end);
    if (end >= size_) break;  // the last pose stays for the test
    if (pose < least_poses) continue;
    const std::size_t distance = end > target ? end - target : target - end;
    const std::size_t best_distance = best > target ? best - target : target - best;
    if (best == 0 || distance <= best_distance) best = end;
    if (end > target) break;  // later boundaries are only farther
  }
  return best == 0 ? pose_start(train_poses) : best;
}

}  // namespace hivecal
