// Fixed-capacity dataset: full is reported, non-finite samples refused, the split is a seeded
// permutation.
#include <gtest/gtest.h>

#include <limits>
#include <cstdlib>
#include <set>
#include <utility>
#include <vector>

#include "hivecal/core/random.hpp"
#include "hivecal/model/dataset.hpp"
#include "testkit/alloc_trap.hpp"

namespace hivecal::dataset_test {
namespace {

TEST(Dataset, ReportsFullInsteadOfDropping) {
  static Dataset<4> dataset;
  dataset.clear();
  EXPECT_EQ(dataset.capacity(), 4u);
  for (int i = 0; i < 4; ++i) {
    Status s = Status::ok;
    EXPECT_NO_HEAP(s = dataset.add(JointVector::Constant(i), Vec3::Constant(i)));
    EXPECT_EQ(s, Status::ok);
  }
  EXPECT_TRUE(dataset.full());
  EXPECT_EQ(dataset.add(JointVector::Zero(), Vec3::Zero()), Status::dataset_full);
  EXPECT_EQ(dataset.size(), 4u);
}

TEST(Dataset, RejectsNonFiniteSamples) {
  static Dataset<8> dataset;
  JointVector q = JointVector::Zero();
  q(3) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(dataset.add(q, Vec3::Zero()), Status::non_finite_input);
  EXPECT_EQ(dataset.add(JointVector::Zero(), Vec3(0, std::numeric_limits<double>::infinity(), 0)),
            Status::non_finite_input);
  EXPECT_EQ(dataset.size(), 0u);
}

TEST(Dataset, SplitIsSeededPermutationWithRequestedShare) {
  static Dataset<100> a;
  static Dataset<100> b;
  for (int i = 0; i < 100; ++i) {
    ASSERT_EQ(a.add(JointVector::Constant(i), Vec3::Constant(i)), Status::ok);
    ASSERT_EQ(b.add(JointVector::Constant(i), Vec3::Constant(i)), Status::ok);
  }
  EXPECT_EQ(a.train().size(), 100u);
  EXPECT_EQ(a.test().size(), 0u);
  Status s = Status::ok;
  EXPECT_NO_HEAP(s = a.split(kDefaultTrainFraction, 5));
  ASSERT_EQ(s, Status::ok);
  ASSERT_EQ(b.split(kDefaultTrainFraction, 5), Status::ok);
  EXPECT_EQ(a.train().size(), 70u);
  EXPECT_EQ(a.test().size(), 30u);
  std::set<double> seen;
  bool moved = false;
  for (std::size_t i = 0; i < 100; ++i) {
    EXPECT_EQ(a.samples()[i].point_m, b.samples()[i].point_m);  // same seed, same order
    seen.insert(a.samples()[i].point_m.x());
    moved = moved || a.samples()[i].point_m.x() != static_cast<double>(i);
  }
  EXPECT_EQ(seen.size(), 100u);  // a permutation: nothing lost or duplicated
  EXPECT_TRUE(moved);
  ASSERT_EQ(b.split(kDefaultTrainFraction, 6), Status::ok);
  EXPECT_NE(a.samples()[0].point_m, b.samples()[0].point_m);
}

TEST(Dataset, SplitErrors) {
  static Dataset<8> dataset;
  dataset.clear();
  EXPECT_EQ(dataset.split(0.7, 1), Status::dataset_empty);
  ASSERT_EQ(dataset.add(JointVector::Zero(), Vec3::Zero()), Status::ok);
  EXPECT_EQ(dataset.split(0.0, 1), Status::invalid_argument);
  EXPECT_EQ(dataset.split(1.5, 1), Status::invalid_argument);
  EXPECT_EQ(dataset.split(std::numeric_limits<double>::quiet_NaN(), 1), Status::invalid_argument);
  EXPECT_EQ(dataset.split(0.2, 1), Status::invalid_argument);  // rounds to zero training samples
  EXPECT_EQ(dataset.split(1.0, 1), Status::ok);
}

/// `poses` poses of three reflectors each (targets 0, 1, 2 added one after another at the same
/// joints), pose k at joints k and points 10 k + target.
void fill_three_targets(int poses, DatasetBase* dataset) {
  dataset->clear();
  for (int k = 0; k < poses; ++k) {
    for (int target = 0; target < 3; ++target) {
      ASSERT_EQ(dataset->add(JointVector::Constant(k), Vec3::Constant(10.0 * k + target), target), Status::ok);
    }
  }
}

/// Pose of a sample of fill_three_targets.
int pose_of(const Sample& s) {
  return static_cast<int>(s.q_rad(0));
}

// Poses of very different sample counts (a stop's repeated readings beside a slow approach's
// single readings): the split keeps poses whole and its training part holds the fraction of the
// samples, to within half the largest pose, whatever the seed (round(0.7 * poses) whole poses
// held from half to nearly all of such a set's samples).
TEST(Dataset, UnequalPosesSplitNearTheFractionOfTheSamples) {
  static Dataset<256> dataset;
  dataset.clear();
  for (int k = 0; k < 30; ++k) {
    const int readings = k % 3 == 0 ? 20 : 1;  // 10 stops of 20 readings, 20 single readings
    for (int r = 0; r < readings; ++r) {
      ASSERT_EQ(dataset.add(JointVector::Constant(k), Vec3::Constant(k)), Status::ok);
    }
  }
  ASSERT_EQ(dataset.size(), 220u);
  for (std::uint64_t seed = 1; seed <= 50; ++seed) {
    Status s = Status::invalid_argument;
    EXPECT_NO_HEAP(s = dataset.split(0.7, seed));
    ASSERT_EQ(s, Status::ok);
    const long train = static_cast<long>(dataset.train().size());
    EXPECT_LE(std::labs(train - 154), 10) << "seed " << seed;  // 0.7 * 220; half of a 20-reading stop
    std::set<double> train_poses;
    for (const Sample& t : dataset.train()) train_poses.insert(t.point_m.x());
    for (const Sample& t : dataset.test()) EXPECT_EQ(train_poses.count(t.point_m.x()), 0u) << "seed " << seed;
    EXPECT_GE(train_poses.size(), 3u);
  }
}

// Several reflectors at one pose: a split that put some of them in training and the others
// in the test would test on what was trained (the same joints), so poses move whole.
TEST(Dataset, SeveralTargetsSplitWholePoses) {
  static Dataset<90> dataset;
  fill_three_targets(30, &dataset);
  EXPECT_EQ(dataset.pose_count(), 30u);
  EXPECT_EQ(dataset.train_count_for(0.7), 21u);  // poses
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    Status s = Status::invalid_argument;
    EXPECT_NO_HEAP(s = dataset.split(0.7, seed));
    ASSERT_EQ(s, Status::ok);
    ASSERT_EQ(dataset.train().size(), 63u);
    ASSERT_EQ(dataset.test().size(), 27u);
    std::set<int> train_poses;
    std::set<int> test_poses;
    std::set<double> seen;
    for (const Sample& t : dataset.train()) train_poses.insert(pose_of(t));
    for (const Sample& t : dataset.test()) test_poses.insert(pose_of(t));
    for (const Sample& t : dataset.samples()) seen.insert(t.point_m.x());
    EXPECT_EQ(train_poses.size(), 21u);
    EXPECT_EQ(test_poses.size(), 9u);
    for (int pose : test_poses) EXPECT_EQ(train_poses.count(pose), 0u) << "seed " << seed << " pose " << pose;
    EXPECT_EQ(seen.size(), 90u);               // nothing lost or duplicated
    for (std::size_t i = 0; i < 90; i += 3) {  // each pose's run stays in target order
      for (std::size_t t = 0; t < 3; ++t) EXPECT_EQ(dataset.samples()[i + t].target, static_cast<int>(t));
    }
  }
  // Seeded: the same seed gives the same order, another seed another.
  ASSERT_EQ(dataset.split(0.7, 3), Status::ok);
  const int first = pose_of(dataset.samples()[0]);
  ASSERT_EQ(dataset.split(0.7, 4), Status::ok);
  ASSERT_EQ(dataset.split(0.7, 3), Status::ok);
  EXPECT_EQ(pose_of(dataset.samples()[0]), first);
  bool differs = false;
  for (std::uint64_t seed = 4; seed < 10 && !differs; ++seed) {
    ASSERT_EQ(dataset.split(0.7, seed), Status::ok);
    differs = pose_of(dataset.samples()[0]) != first;
  }
  EXPECT_TRUE(differs);
  // No test part (--split 1): every sample trains.
  ASSERT_EQ(dataset.split(1.0, 3), Status::ok);
  EXPECT_EQ(dataset.train().size(), 90u);
  EXPECT_EQ(dataset.test().size(), 0u);
}

TEST(Dataset, SeveralTargetsFoldsHoldOutWholePoses) {
  static Dataset<90> dataset;
  fill_three_targets(10, &dataset);
  EXPECT_EQ(dataset.split_fold(0, 11, 1), Status::invalid_argument);  // more folds than poses
  std::set<int> held_out;
  for (std::size_t fold = 0; fold < 4; ++fold) {
    ASSERT_EQ(dataset.split_fold(fold, 4, 7), Status::ok);
    std::set<int> train_poses;
    for (const Sample& t : dataset.train()) train_poses.insert(pose_of(t));
    for (const Sample& t : dataset.test()) {
      EXPECT_EQ(train_poses.count(pose_of(t)), 0u);
      held_out.insert(pose_of(t));
    }
    EXPECT_EQ(dataset.test().size() % 3, 0u);
    EXPECT_EQ(train_poses.size() + dataset.test().size() / 3, 10u);
  }
  EXPECT_EQ(held_out.size(), 10u);                      // every pose held out once
  ASSERT_EQ(dataset.split_fold(9, 10, 7), Status::ok);  // leave one pose out
  EXPECT_EQ(dataset.test().size(), 3u);
}

// One target, joints that differ from one sample to the next: every sample is its own pose and
// the draws are those of a plain Fisher-Yates (the goldens of every job depend on them).
TEST(Dataset, OneTargetSplitsSamples) {
  static Dataset<30> dataset;
  dataset.clear();
  for (int i = 0; i < 30; ++i) ASSERT_EQ(dataset.add(JointVector::Constant(0.01 * i), Vec3::Constant(i)), Status::ok);
  EXPECT_EQ(dataset.pose_count(), 30u);
  ASSERT_EQ(dataset.split(0.7, 5), Status::ok);
  EXPECT_EQ(dataset.train().size(), 21u);
  for (std::size_t fold = 0; fold < 4; ++fold) {  // folds of samples: [k n / 4, (k + 1) n / 4)
    ASSERT_EQ(dataset.split_fold(fold, 4, 5), Status::ok);
    EXPECT_EQ(dataset.test().size(), (fold + 1) * 30 / 4 - fold * 30 / 4);
  }
}

// One target read three times at each stop (equal joints, consecutive): the readings of a stop
// are one pose, never split between training and test (they would test the fit on its own data).
TEST(Dataset, RepeatedReadingsOfOneTargetStayTogether) {
  static Dataset<30> dataset;
  dataset.clear();
  const auto pose_of = [](const Sample& s) { return static_cast<int>(s.q_rad[0] * 100.0 + 0.5); };
  for (int i = 0; i < 30; ++i)
    ASSERT_EQ(dataset.add(JointVector::Constant(0.01 * (i / 3)), Vec3::Constant(i)), Status::ok);
  EXPECT_EQ(dataset.pose_count(), 10u);
  ASSERT_EQ(dataset.split(0.7, 5), Status::ok);
  EXPECT_EQ(dataset.train().size(), 21u);  // 7 of 10 poses, 3 readings each
  std::set<int> train_poses;
  for (const Sample& t : dataset.train()) train_poses.insert(pose_of(t));
  for (const Sample& t : dataset.test()) EXPECT_EQ(train_poses.count(pose_of(t)), 0u);
  EXPECT_EQ(train_poses.size(), 7u);
  for (std::size_t fold = 0; fold < 5; ++fold) {  // 5 folds of 2 poses
    ASSERT_EQ(dataset.split_fold(fold, 5, 5), Status::ok);
    EXPECT_EQ(dataset.test().size(), 6u);
  }
  EXPECT_EQ(dataset.split_fold(0, 11, 5), Status::invalid_argument);  // more folds than poses
}

// Samples of one stop of the robot (joints within encoder noise) are one point per target;
// stops that come back later in the set are recognised; the count stops at its limit.
TEST(Dataset, CountsDistinctPointsNotSamples) {
  static Dataset<400> dataset;
  dataset.clear();
  const auto stop = [](int k) { return JointVector::Constant(0.1 * k); };
  for (int repeat = 0; repeat < 3; ++repeat) {
    for (int k = 0; k < 5; ++k) {
      for (int i = 0; i < 10; ++i) {
        const JointVector noise = JointVector::Constant((i % 3 - 1) * 2e-4);  // within 1e-3 rad
        ASSERT_EQ(dataset.add(stop(k) + noise, Vec3::Zero(), 0), Status::ok);
        ASSERT_EQ(dataset.add(stop(k) + noise, Vec3::Zero(), 1), Status::ok);  // a second reflector
      }
    }
  }
  std::size_t points = 0;
  EXPECT_NO_HEAP(points = distinct_points(dataset.samples()));
  EXPECT_EQ(points, 10u) << "5 stops x 2 targets, whatever the samples and repeats";
  JointVector moved = stop(2);
  moved(4) += 2e-3;  // beyond the tolerance in one joint: another pose
  ASSERT_EQ(dataset.add(moved, Vec3::Zero(), 0), Status::ok);
  EXPECT_EQ(distinct_points(dataset.samples()), 11u);
  dataset.clear();
  for (int k = 0; k < 100; ++k) ASSERT_EQ(dataset.add(stop(k), Vec3::Zero()), Status::ok);
  EXPECT_EQ(distinct_points(dataset.samples()), kDistinctPointLimit);
}

// A robot creeping into a stop (joints a few mrad apart, each reading its own pose) is one
// configuration of the arm; the stops, any targets, are counted; the count stops at its limit.
TEST(Dataset, CountsConfigurationsNotCreepingPoses) {
  static Dataset<400> dataset;
  dataset.clear();
  const auto stop = [](int k) { return JointVector::Constant(0.1 * k); };
  for (int k = 0; k < 6; ++k) {
    for (int i = 0; i < 20; ++i) {
      const JointVector creep = JointVector::Constant(-8e-4 * i);  // 15 mrad in all: within 1 degree
      ASSERT_EQ(dataset.add(stop(k) + creep, Vec3::Zero(), 0), Status::ok);
      ASSERT_EQ(dataset.add(stop(k) + creep, Vec3::Zero(), 1), Status::ok);
    }
  }
  std::size_t configurations = 0;
  EXPECT_NO_HEAP(configurations = distinct_configurations(dataset.samples()));
  EXPECT_EQ(configurations, 6u);
  EXPECT_EQ(dataset.pose_count(), 120u);  // each creeping reading is a pose of its own
  JointVector moved = stop(2);
  moved(0) += 0.03;  // two degrees in one joint: another configuration
  ASSERT_EQ(dataset.add(moved, Vec3::Zero(), 0), Status::ok);
  EXPECT_EQ(distinct_configurations(dataset.samples()), 7u);
  dataset.clear();
  for (int k = 0; k < 100; ++k) ASSERT_EQ(dataset.add(stop(k), Vec3::Zero()), Status::ok);
  EXPECT_EQ(distinct_configurations(dataset.samples()), kDistinctPointLimit);
}

}  // namespace
}  // namespace hivecal::dataset_test

namespace hivecal::dataset_test {
namespace {

// The dataset's reorderings as they were first written, one sample moved at a time: an
// insertion sort by index, a pose's block moved down over the gap sample by sample, the fold
// rotated left one sample at a time. The library's n log n sort and block rotations must give
// these orders exactly: every job's split, and so every golden digest, depends on them.
using Samples = std::vector<Sample>;  ///< the reference's storage

void reference_sort_by_index(Samples* v, std::size_t count) {
  for (std::size_t i = 1; i < count; ++i) {
    const Sample moving = (*v)[i];
    std::size_t j = i;
    for (; j > 0 && (*v)[j - 1].index > moving.index; --j) (*v)[j] = (*v)[j - 1];
    (*v)[j] = moving;
  }
}

std::size_t reference_pose_end(const Samples& v, std::size_t size, std::size_t begin) {
  std::size_t end = begin + 1;
  while (end < size && v[end].q_rad == v[begin].q_rad) ++end;
  return end;
}

void reference_shuffle_poses(Samples* v, std::size_t size, std::uint64_t seed) {
  reference_sort_by_index(v, size);
  std::size_t poses = 0;
  for (std::size_t i = 0; i < size; i = reference_pose_end(*v, size, i)) ++poses;
  Random random(seed);
  for (std::size_t placed_end = 0, remaining = poses; remaining > 1; --remaining) {
    const auto pick = static_cast<std::size_t>(random.below(remaining));
    std::size_t begin = placed_end;
    for (std::size_t k = 0; k < pick; ++k) begin = reference_pose_end(*v, size, begin);
    const std::size_t end = reference_pose_end(*v, size, begin);
    for (std::size_t i = begin; i < end; ++i) {
      const Sample moving = (*v)[i];
      for (std::size_t j = i; j > placed_end + (i - begin); --j) (*v)[j] = (*v)[j - 1];
      (*v)[placed_end + (i - begin)] = moving;
    }
    placed_end += end - begin;
  }
}

void reference_rotate_left(Samples* v, std::size_t begin, std::size_t size, std::size_t by) {
  for (std::size_t r = 0; r < by; ++r) {
    const Sample first = (*v)[begin];
    for (std::size_t i = begin; i + 1 < size; ++i) (*v)[i] = (*v)[i + 1];
    (*v)[size - 1] = first;
  }
}

/// Each sample's index and target, in storage order.
std::vector<std::pair<std::uint32_t, int>> order_of(const DatasetBase& dataset) {
  std::vector<std::pair<std::uint32_t, int>> order;
  for (const Sample& s : dataset.samples()) order.emplace_back(s.index, s.target);
  for (const Sample& s : dataset.set_aside()) order.emplace_back(s.index, s.target);
  return order;
}

std::vector<std::pair<std::uint32_t, int>> order_of(const Samples& v) {
  std::vector<std::pair<std::uint32_t, int>> order;
  for (const Sample& s : v) order.emplace_back(s.index, s.target);
  return order;
}

TEST(Dataset, ReordersExactlyAsOneSampleAtATime) {
  static Dataset<3000> dataset;
  Random random(2026);
  for (int trial = 0; trial < 200; ++trial) {
    // Poses of 1 to 3 samples (targets or repeated readings), some set aside; the last sets
    // have more poses than the shuffle's directory has blocks.
    dataset.clear();
    const auto poses = static_cast<int>(3 + random.below(trial < 100 ? 20 : trial < 180 ? 130 : 900));
    for (int p = 0; p < poses; ++p) {
      const auto readings = static_cast<int>(1 + random.below(3));
      for (int k = 0; k < readings; ++k) {
        ASSERT_EQ(dataset.add(JointVector::Constant(p), Vec3(p, k, trial), k), Status::ok);
      }
    }
    std::vector<std::uint32_t> aside;
    for (std::size_t a = random.below(4); a > 0; --a)
      aside.push_back(static_cast<std::uint32_t>(random.below(dataset.size())));
    const std::uint64_t seed = random.next();
    // A shuffled storage first (a previous split), then set_aside sorts and partitions.
    ASSERT_EQ(dataset.split(0.7, seed ^ 1U), Status::ok);
    Samples v(dataset.samples().begin(), dataset.samples().end());
    EXPECT_NO_HEAP(dataset.set_aside(Span<const std::uint32_t>(aside.data(), aside.size())));
    reference_sort_by_index(&v, v.size());
    Samples kept;
    Samples gone;
    for (const Sample& s : v) {
      bool out = false;
      for (std::uint32_t index : aside) out = out || s.index == index;
      (out ? gone : kept).push_back(s);
    }
    const std::size_t size = kept.size();
    v = kept;
    v.insert(v.end(), gone.begin(), gone.end());
    ASSERT_EQ(order_of(dataset), order_of(v)) << "set_aside, trial " << trial;
    // A split of whole poses.
    if (dataset.pose_count() < dataset.size()) {
      EXPECT_NO_HEAP(dataset.split(0.7, seed));
      reference_shuffle_poses(&v, size, seed);
      ASSERT_EQ(order_of(dataset), order_of(v)) << "split, trial " << trial;
    }
    // A fold: the poses shuffled again, the fold's block rotated to the end.
    const std::size_t folds = 2 + random.below(dataset.pose_count() - 1);
    const std::size_t fold = random.below(folds);
    EXPECT_NO_HEAP(dataset.split_fold(fold, folds, seed));
    const std::size_t fold_begin = dataset.size() - dataset.test().size();
    if (dataset.pose_count() < dataset.size()) {
      reference_shuffle_poses(&v, size, seed);
    } else {
      reference_sort_by_index(&v, size);
      Random draws(seed);
      for (std::size_t i = size - 1; i > 0; --i) std::swap(v[i], v[draws.below(i + 1)]);
    }
    std::size_t begin = 0;
    std::size_t at_pose = 0;
    const std::size_t fold_first_pose = fold * dataset.pose_count() / folds;
    while (at_pose < fold_first_pose) {
      begin = reference_pose_end(v, size, begin);
      ++at_pose;
    }
    reference_rotate_left(&v, begin, size, size - fold_begin);
    ASSERT_EQ(order_of(dataset), order_of(v)) << "split_fold, trial " << trial;
  }
}

TEST(PoseRunEnd, ARunOfEqualJointsIsOnePoseAnyDifferenceEndsIt) {
  Sample s[5];
  for (Sample& x : s) x.q_rad << 0.1, -1.0, 1.2, -0.4, 1.5, 0.3;
  s[1].target = 1;         // another reflector at the same joints: the same pose
  s[3].q_rad(5) += 1e-12;  // the least difference: a new pose
  const Span<const Sample> all(s, 5);
  EXPECT_EQ(pose_run_end(all, 0), 3u);
  EXPECT_EQ(pose_run_end(all, 1), 3u);
  EXPECT_EQ(pose_run_end(all, 3), 4u);  // s[4] has s[0]'s joints, not s[3]'s
  EXPECT_EQ(pose_run_end(all, 4), 5u);
}

TEST(Dataset, ReadingsFitAJointCountWhenTheJointsBeyondItAreZero) {
  static Dataset<4> dataset;
  dataset.clear();
  JointVector q;
  q << 0.1, -0.2, 0.3, 0.4;
  ASSERT_EQ(dataset.add(q, Vec3::Zero()), Status::ok);
  bool fits = false;
  EXPECT_NO_HEAP(fits = readings_fit_joint_count(dataset.samples(), 4));
  EXPECT_TRUE(fits);
  EXPECT_TRUE(readings_fit_joint_count(dataset.samples(), kMaxJoints));
  EXPECT_FALSE(readings_fit_joint_count(dataset.samples(), 3));
  EXPECT_TRUE(readings_fit_joint_count(Span<const Sample>(), 1));
}

/// Reverses the first `count` samples by exchanges, as a caller that reorders does.
void reverse_first(DatasetBase* dataset, std::size_t count) {
  for (std::size_t i = 0; i < count / 2; ++i) dataset->swap_samples(i, count - 1 - i);
}

TEST(Dataset, RestoreSplitMakesTheLastSplitsOrderAgain) {
  static Dataset<64> dataset;
  dataset.clear();
  for (int i = 0; i < 60; ++i) {  // poses of two samples (two targets) and of one
    const int target = i % 3 == 1 ? 1 : 0;
    const int pose = i - (target == 1 ? 1 : 0);
    ASSERT_EQ(dataset.add(JointVector::Constant(pose), Vec3::Constant(i), target), Status::ok);
  }
  reverse_first(&dataset, dataset.size());  // no split yet: back in the order of add()
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = dataset.restore_split());
  EXPECT_EQ(status, Status::ok);
  for (std::size_t i = 0; i < dataset.size(); ++i) EXPECT_EQ(dataset.samples()[i].index, i);
  ASSERT_EQ(dataset.split(0.7, 9), Status::ok);
  const auto split = order_of(dataset);
  const std::size_t train = dataset.train().size();
  reverse_first(&dataset, train);
  ASSERT_NE(order_of(dataset), split);
  EXPECT_NO_HEAP(status = dataset.restore_split());
  EXPECT_EQ(status, Status::ok);
  EXPECT_EQ(order_of(dataset), split);
  EXPECT_EQ(dataset.train().size(), train);
  ASSERT_EQ(dataset.split_fold(2, 5, 4), Status::ok);
  const auto fold = order_of(dataset);
  reverse_first(&dataset, dataset.train().size());
  EXPECT_EQ(dataset.restore_split(), Status::ok);
  EXPECT_EQ(order_of(dataset), fold);
  dataset.set_aside(Span<const std::uint32_t>());  // a set aside discards the split
  reverse_first(&dataset, dataset.size());
  EXPECT_EQ(dataset.restore_split(), Status::ok);
  for (std::size_t i = 0; i < dataset.size(); ++i) EXPECT_EQ(dataset.samples()[i].index, i);
}

}  // namespace
}  // namespace hivecal::dataset_test
