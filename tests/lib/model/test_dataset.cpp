// Fixed-capacity dataset: full is reported, non-finite samples refused, the split is a seeded
// permutation.
#include <gtest/gtest.h>

#include <limits>
#include <set>

#include "hivecal/model/dataset.hpp"
#include "testkit/alloc_trap.hpp"

namespace hivecal {
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

}  // namespace
}  // namespace hivecal
