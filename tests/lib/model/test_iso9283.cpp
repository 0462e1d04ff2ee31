// ISO 9283 pose accuracy and repeatability (model/iso9283.hpp): the formulas on a hand-worked
// case, and on simulated reaches with a known bias and spread (many cycles: the figures the
// normal distribution gives).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "hivecal/core/random.hpp"
#include "hivecal/model/iso9283.hpp"
#include "testkit/alloc_trap.hpp"

namespace hivecal::iso9283_test {
namespace {

TEST(Iso9283, HandWorkedPose) {
  // Four reaches on a square of side 2 around (10, 0, 0), commanded at the origin.
  const Vec3 reaches[] = {Vec3(11, 1, 0), Vec3(9, 1, 0), Vec3(9, -1, 0), Vec3(11, -1, 0)};
  PoseAccuracy pose;
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = pose_accuracy(Span<const Vec3>(reaches, 4), Vec3::Zero(), &pose));
  ASSERT_EQ(status, Status::ok);
  EXPECT_EQ(pose.cycles, 4u);
  EXPECT_DOUBLE_EQ(pose.accuracy_norm_m, 10.0);
  EXPECT_DOUBLE_EQ(pose.accuracy_m.x(), 10.0);
  EXPECT_DOUBLE_EQ(pose.mean_distance_m, std::sqrt(2.0));  // every reach sqrt(2) from the barycentre
  EXPECT_DOUBLE_EQ(pose.distance_sigma_m, 0.0);
  EXPECT_DOUBLE_EQ(pose.repeatability_m, std::sqrt(2.0));
  // One reach farther out: S_l with n - 1.
  const Vec3 uneven[] = {Vec3(1, 0, 0), Vec3(-1, 0, 0), Vec3(0, 4, 0), Vec3(0, -4, 0)};
  ASSERT_EQ(pose_accuracy(Span<const Vec3>(uneven, 4), Vec3::Zero(), &pose), Status::ok);
  EXPECT_DOUBLE_EQ(pose.mean_distance_m, 2.5);
  EXPECT_DOUBLE_EQ(pose.distance_sigma_m, std::sqrt(4 * 2.25 / 3.0));
  EXPECT_DOUBLE_EQ(pose.repeatability_m, 2.5 + 3.0 * std::sqrt(3.0));
}

TEST(Iso9283, KnownBiasAndSpread) {
  // Reaches N(commanded + bias, sigma^2 I): AP_P -> |bias|; l is Maxwell-distributed, so
  // lb -> 2 sigma sqrt(2/pi) and S_l -> sigma sqrt(3 - 8/pi): RP_l -> 3.615 sigma.
  const Vec3 commanded(0.4, -0.2, 0.6);
  const Vec3 bias(30e-6, -40e-6, 0.0);  // 50 um
  const double sigma_m = 10e-6;
  Random random(9);
  std::vector<Vec3> reaches;
  for (int i = 0; i < 20000; ++i) {
    reaches.emplace_back(commanded + bias + sigma_m * Vec3(random.normal(), random.normal(), random.normal()));
  }
  PoseAccuracy pose;
  ASSERT_EQ(pose_accuracy(Span<const Vec3>(reaches.data(), reaches.size()), commanded, &pose), Status::ok);
  const double pi = 3.141592653589793;
  EXPECT_NEAR(pose.accuracy_norm_m, 50e-6, 0.5e-6);
  EXPECT_NEAR(pose.mean_distance_m, 2.0 * sigma_m * std::sqrt(2.0 / pi), 0.02 * sigma_m);
  EXPECT_NEAR(pose.distance_sigma_m, sigma_m * std::sqrt(3.0 - 8.0 / pi), 0.02 * sigma_m);
  EXPECT_NEAR(pose.repeatability_m, 3.615 * sigma_m, 0.05 * sigma_m);
}

TEST(Iso9283, RefusesTooFewOrNonFiniteReaches) {
  PoseAccuracy pose;
  const Vec3 one[] = {Vec3::Zero()};
  EXPECT_EQ(pose_accuracy(Span<const Vec3>(one, 1), Vec3::Zero(), &pose), Status::invalid_argument);
  const Vec3 bad[] = {Vec3::Zero(), Vec3(std::nan(""), 0, 0)};
  EXPECT_EQ(pose_accuracy(Span<const Vec3>(bad, 2), Vec3::Zero(), &pose), Status::non_finite_input);
}

}  // namespace
}  // namespace hivecal::iso9283_test
