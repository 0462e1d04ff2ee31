#include <gtest/gtest.h>

#include <limits>

#include "alloc_trap.hpp"
#include "hivecal/random.hpp"
#include "hivecal/rigid_fit.hpp"
#include "test_data.hpp"

namespace hivecal {
namespace {

Mat3 random_rotation(Random* random) {
  // Axis-angle with own trig: Rodrigues' formula.
  Vec3 axis;
  axis << random->normal(), random->normal(), random->normal();  // defined order (not constructor arguments)
  axis.normalize();
  const double angle = random->uniform(-3.1, 3.1);
  Mat3 k;
  k << 0, -axis.z(), axis.y(), axis.z(), 0, -axis.x(), -axis.y(), axis.x(), 0;
  return Mat3::Identity() + math::sin(angle) * k + (1.0 - math::cos(angle)) * k * k;
}

TEST(RigidFit, RecoversRandomTransformsExactly) {
  Random random(21);
  for (int trial = 0; trial < 500; ++trial) {
    RigidTransform truth;
    truth.rotation = random_rotation(&random);
    truth.translation_m << random.uniform(-5, 5), random.uniform(-5, 5), random.uniform(-5, 5);
    Vec3 source[20];
    Vec3 target[20];
    const auto n = static_cast<std::size_t>(3 + random.below(17));
    for (std::size_t i = 0; i < n; ++i) {
      source[i] << random.uniform(-1, 1), random.uniform(-1, 1), random.uniform(-1, 1);
      target[i] = truth.apply(source[i]);
    }
    RigidTransform fit;
    Status status = Status::ok;
    EXPECT_NO_HEAP(status = fit_rigid_transform(Span<const Vec3>(source, n), Span<const Vec3>(target, n), {}, &fit));
    ASSERT_EQ(status, Status::ok);
    EXPECT_LT((fit.rotation - truth.rotation).norm(), 1e-12);
    EXPECT_LT((fit.translation_m - truth.translation_m).norm(), 1e-12);
    EXPECT_NEAR(fit.rotation.determinant(), 1.0, 1e-12);
  }
}

TEST(RigidFit, NeverReturnsAReflection) {
  // Target is a mirror image: the best proper rotation, never det = -1.
  Vec3 source[4] = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  Vec3 target[4];
  for (int i = 0; i < 4; ++i) target[i] = Vec3(source[i].x(), source[i].y(), -source[i].z());
  RigidTransform fit;
  ASSERT_EQ(fit_rigid_transform(source, target, {}, &fit), Status::ok);
  EXPECT_NEAR(fit.rotation.determinant(), 1.0, 1e-12);
}

TEST(RigidFit, WeightsSelectThePairsThatCount) {
  Random random(22);
  RigidTransform truth;
  truth.rotation = random_rotation(&random);
  truth.translation_m << 1, 2, 3;
  Vec3 source[8];
  Vec3 target[8];
  double weights[8];
  for (int i = 0; i < 8; ++i) {
    source[i] << random.uniform(-1, 1), random.uniform(-1, 1), random.uniform(-1, 1);
    target[i] = truth.apply(source[i]);
    weights[i] = 1.0;
  }
  target[7] += Vec3(0.5, -0.5, 0.2);  // an outlier
  weights[7] = 0.0;
  RigidTransform fit;
  ASSERT_EQ(fit_rigid_transform(source, target, weights, &fit), Status::ok);
  EXPECT_LT((fit.translation_m - truth.translation_m).norm(), 1e-12);
  ASSERT_EQ(fit_rigid_transform(source, target, {}, &fit), Status::ok);
  EXPECT_GT((fit.translation_m - truth.translation_m).norm(), 1e-3);
}

TEST(RigidFit, DegenerateInputsGetSpecificErrors) {
  RigidTransform fit;
  Vec3 two[2] = {Vec3(0, 0, 0), Vec3(1, 0, 0)};
  EXPECT_EQ(fit_rigid_transform(two, two, {}, &fit), Status::too_few_samples);
  Vec3 collinear[5] = {Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(2, 2, 2), Vec3(3, 3, 3), Vec3(-1, -1, -1)};
  EXPECT_EQ(fit_rigid_transform(collinear, collinear, {}, &fit), Status::degenerate_geometry);
  Vec3 same[4] = {Vec3(1, 2, 3), Vec3(1, 2, 3), Vec3(1, 2, 3), Vec3(1, 2, 3)};
  EXPECT_EQ(fit_rigid_transform(same, same, {}, &fit), Status::degenerate_geometry);
  Vec3 with_nan[3] = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, std::numeric_limits<double>::quiet_NaN(), 0)};
  EXPECT_EQ(fit_rigid_transform(with_nan, with_nan, {}, &fit), Status::non_finite_input);
  Vec3 with_inf[3] = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, std::numeric_limits<double>::infinity(), 0)};
  EXPECT_EQ(fit_rigid_transform(with_inf, with_inf, {}, &fit), Status::non_finite_input);
  Vec3 good[3] = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  double negative[3] = {1.0, -1.0, 1.0};
  EXPECT_EQ(fit_rigid_transform(good, good, negative, &fit), Status::invalid_argument);
  double short_weights[2] = {1.0, 1.0};
  EXPECT_EQ(fit_rigid_transform(good, good, short_weights, &fit), Status::invalid_argument);
  EXPECT_EQ(fit_rigid_transform(good, Span<const Vec3>(good, 2), {}, &fit), Status::invalid_argument);
  EXPECT_EQ(fit_rigid_transform(good, good, {}, &fit), Status::ok);
}

TEST(RigidFit, FarFromOriginStaysAccurate) {
  // Tracker coordinates kilometres from the origin: sums are kept relative to the first pair.
  Random random(23);
  RigidTransform truth;
  truth.rotation = random_rotation(&random);
  truth.translation_m << 3000.0, -2000.0, 1000.0;
  Vec3 source[50];
  Vec3 target[50];
  for (int i = 0; i < 50; ++i) {
    source[i] = Vec3(1000.0, 1000.0, 1000.0) + Vec3(random.uniform(-1, 1), random.uniform(-1, 1), random.uniform(-1, 1));
    target[i] = truth.apply(source[i]);
  }
  RigidTransform fit;
  ASSERT_EQ(fit_rigid_transform(source, target, {}, &fit), Status::ok);
  for (int i = 0; i < 50; ++i) EXPECT_LT((fit.apply(source[i]) - target[i]).norm(), 1e-9);
}

}  // namespace
}  // namespace hivecal
