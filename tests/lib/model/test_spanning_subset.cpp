// Spanning subsets: every cluster of poses gets a sample before any gets two, the choice is
// deterministic and ascending, wrapped joints and other targets count as they should.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <set>
#include <vector>

#include "hivecal/core/math.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/model/spanning_subset.hpp"
#include "testkit/alloc_trap.hpp"

namespace hivecal::spanning_subset_test {
namespace {

Sample sample_at(const JointVector& q_rad, int target = 0) {
  Sample s;
  s.q_rad = q_rad;
  s.target = target;
  return s;
}

TEST(SpanningSubset, WrappedJointsAreOnePose) {
  const JointVector q = (JointVector() << 0.1, -1.2, 2.0, -0.4, 1.5, 3.0).finished();
  JointVector turned = q;
  turned(0) += 2.0 * math::kPi;
  turned(5) -= 4.0 * math::kPi;
  EXPECT_NEAR(pose_distance_sq(sample_at(q), sample_at(turned), kSixJoints), 0.0, 1e-24);
  JointVector across = q;  // 3.0 and -3.0 rad are 0.28 rad apart, not 6
  across(5) = -3.0;
  EXPECT_NEAR(pose_distance_sq(sample_at(q), sample_at(across), kSixJoints), std::pow(2.0 * math::kPi - 6.0, 2), 1e-12);
  EXPECT_NEAR(pose_distance_sq(sample_at(q, 0), sample_at(q, 1), kSixJoints), math::kPi * math::kPi, 1e-12);
}

// Many samples in a few tight clusters of poses (a robot's stops, or a grid that favours
// one region): a subset of as many samples as clusters takes one from each.
TEST(SpanningSubset, TakesOneSampleOfEveryClusterFirst) {
  for (std::uint64_t seed = 1; seed <= 50; ++seed) {
    Random rng(seed);
    constexpr int kClusters = 12;
    JointVector centres[kClusters];
    for (JointVector& c : centres) {
      for (int j = 0; j < kSixJoints; ++j) c(j) = rng.uniform(-math::kPi, math::kPi);
    }
    std::vector<Sample> samples;
    std::vector<int> cluster_of;
    for (int i = 0; i < 600; ++i) {
      // uneven: cluster 0 holds half the samples
      const int c = rng.uniform(0.0, 1.0) < 0.5 ? 0 : 1 + static_cast<int>(rng.below(kClusters - 1));
      JointVector q = centres[c];
      for (int j = 0; j < kSixJoints; ++j) q(j) += rng.uniform(-1e-3, 1e-3);
      samples.push_back(sample_at(q));
      cluster_of.push_back(c);
    }
    std::vector<double> scratch(samples.size());
    std::uint32_t chosen[kClusters] = {};
    std::size_t count = 0;
    EXPECT_NO_HEAP(count = spanning_subset(Span<const Sample>(samples.data(), samples.size()), kSixJoints,
                                           Span<double>(scratch.data(), scratch.size()), Span<std::uint32_t>(chosen)));
    ASSERT_EQ(count, static_cast<std::size_t>(kClusters)) << "seed " << seed;
    std::set<int> clusters;
    for (std::size_t k = 0; k < count; ++k) {
      clusters.insert(cluster_of[chosen[k]]);
      if (k > 0) {
        EXPECT_LT(chosen[k - 1], chosen[k]);  // ascending, distinct
      }
    }
    EXPECT_EQ(clusters.size(), static_cast<std::size_t>(kClusters)) << "seed " << seed;
    EXPECT_EQ(chosen[0], 0u);  // the first sample starts the set
  }
}

TEST(SpanningSubset, IsDeterministicAndBoundedByTheRoom) {
  Random rng(7);
  std::vector<Sample> samples(300);
  for (Sample& s : samples) {
    for (int j = 0; j < kSixJoints; ++j) s.q_rad(j) = rng.uniform(-3.0, 3.0);
    s.target = rng.uniform(0.0, 1.0) < 0.3 ? 1 : 0;
  }
  std::vector<double> scratch(samples.size());
  const Span<const Sample> all(samples.data(), samples.size());
  std::uint32_t a[40] = {};
  std::uint32_t b[40] = {};
  ASSERT_EQ(spanning_subset(all, kSixJoints, Span<double>(scratch.data(), scratch.size()), Span<std::uint32_t>(a)),
            40u);
  ASSERT_EQ(spanning_subset(all, kSixJoints, Span<double>(scratch.data(), scratch.size()), Span<std::uint32_t>(b)),
            40u);
  for (int k = 0; k < 40; ++k) EXPECT_EQ(a[k], b[k]);
  int second_target = 0;
  for (std::uint32_t position : a) second_target += samples[position].target;
  EXPECT_GT(second_target, 0);  // both reflectors are represented

  std::uint32_t room[400] = {};  // more room than samples: every sample, in order
  ASSERT_EQ(spanning_subset(all, kSixJoints, Span<double>(scratch.data(), scratch.size()), Span<std::uint32_t>(room)),
            300u);
  for (std::uint32_t k = 0; k < 300; ++k) EXPECT_EQ(room[k], k);

  // Too little scratch, no room or no samples: nothing chosen.
  EXPECT_EQ(spanning_subset(all, kSixJoints, Span<double>(scratch.data(), 299), Span<std::uint32_t>(a)), 0u);
  EXPECT_EQ(spanning_subset(all, kSixJoints, Span<double>(scratch.data(), scratch.size()), Span<std::uint32_t>()), 0u);
  EXPECT_EQ(spanning_subset(Span<const Sample>(), kSixJoints, Span<double>(scratch.data(), scratch.size()),
                            Span<std::uint32_t>(a)),
            0u);
}

}  // namespace
}  // namespace hivecal::spanning_subset_test
