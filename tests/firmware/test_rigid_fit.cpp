// Rigid fit (Kabsch) on the MCU: exact recovery, reflection guard, weights, and the
// specific error of each degenerate input.
#include <limits>

#include "harness.hpp"
#include "hivecal/random.hpp"
#include "hivecal/rigid_fit.hpp"

namespace hivecal {
namespace {

Mat3 random_rotation(Random* random) {
  // Axis-angle with own trig: Rodrigues' formula.
  Vec3 axis(random->normal(), random->normal(), random->normal());
  axis.normalize();
  const double angle = random->uniform(-3.1, 3.1);
  Mat3 k;
  k << 0, -axis.z(), axis.y(), axis.z(), 0, -axis.x(), -axis.y(), axis.x(), 0;
  return Mat3::Identity() + math::sin(angle) * k + (1.0 - math::cos(angle)) * k * k;
}

FW_TEST(RigidFit, RecoversRandomTransformsExactly) {
  Random random(21);
  for (int trial = 0; trial < 50; ++trial) {
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
    FW_ASSERT_EQ(fit_rigid_transform(Span<const Vec3>(source, n), Span<const Vec3>(target, n), {}, &fit), Status::ok);
    FW_CHECK_LT((fit.rotation - truth.rotation).norm(), 1e-12);
    FW_CHECK_LT((fit.translation_m - truth.translation_m).norm(), 1e-12);
    FW_CHECK_NEAR(fit.rotation.determinant(), 1.0, 1e-12);
  }
}

FW_TEST(RigidFit, NeverReturnsAReflection) {
  Vec3 source[4] = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  Vec3 target[4];
  for (int i = 0; i < 4; ++i) target[i] = Vec3(source[i].x(), source[i].y(), -source[i].z());
  RigidTransform fit;
  FW_ASSERT_EQ(fit_rigid_transform(source, target, {}, &fit), Status::ok);
  FW_CHECK_NEAR(fit.rotation.determinant(), 1.0, 1e-12);
}

FW_TEST(RigidFit, WeightsSelectThePairsThatCount) {
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
  FW_ASSERT_EQ(fit_rigid_transform(source, target, weights, &fit), Status::ok);
  FW_CHECK_LT((fit.translation_m - truth.translation_m).norm(), 1e-12);
  FW_ASSERT_EQ(fit_rigid_transform(source, target, {}, &fit), Status::ok);
  FW_CHECK_GT((fit.translation_m - truth.translation_m).norm(), 1e-3);
}

FW_TEST(RigidFit, DegenerateInputsGetSpecificErrors) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  RigidTransform fit;
  Vec3 two[2] = {Vec3(0, 0, 0), Vec3(1, 0, 0)};
  FW_CHECK_EQ(fit_rigid_transform(two, two, {}, &fit), Status::too_few_samples);
  Vec3 collinear[5] = {Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(2, 2, 2), Vec3(3, 3, 3), Vec3(-1, -1, -1)};
  FW_CHECK_EQ(fit_rigid_transform(collinear, collinear, {}, &fit), Status::degenerate_geometry);
  Vec3 same[4] = {Vec3(1, 2, 3), Vec3(1, 2, 3), Vec3(1, 2, 3), Vec3(1, 2, 3)};
  FW_CHECK_EQ(fit_rigid_transform(same, same, {}, &fit), Status::degenerate_geometry);
  Vec3 with_nan[3] = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, nan, 0)};
  FW_CHECK_EQ(fit_rigid_transform(with_nan, with_nan, {}, &fit), Status::non_finite_input);
  Vec3 with_inf[3] = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, inf, 0)};
  FW_CHECK_EQ(fit_rigid_transform(with_inf, with_inf, {}, &fit), Status::non_finite_input);
  Vec3 good[3] = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  double negative[3] = {1.0, -1.0, 1.0};
  FW_CHECK_EQ(fit_rigid_transform(good, good, negative, &fit), Status::invalid_argument);
  double short_weights[2] = {1.0, 1.0};
  FW_CHECK_EQ(fit_rigid_transform(good, good, short_weights, &fit), Status::invalid_argument);
  FW_CHECK_EQ(fit_rigid_transform(good, Span<const Vec3>(good, 2), {}, &fit), Status::invalid_argument);
  FW_CHECK_EQ(fit_rigid_transform(good, good, {}, &fit), Status::ok);
}

FW_TEST(RigidFit, FarFromOriginStaysAccurate) {
  Random random(23);
  RigidTransform truth;
  truth.rotation = random_rotation(&random);
  truth.translation_m << 3000.0, -2000.0, 1000.0;
  Vec3 source[50];
  Vec3 target[50];
  for (int i = 0; i < 50; ++i) {
    source[i] =
        Vec3(1000.0, 1000.0, 1000.0) + Vec3(random.uniform(-1, 1), random.uniform(-1, 1), random.uniform(-1, 1));
    target[i] = truth.apply(source[i]);
  }
  RigidTransform fit;
  FW_ASSERT_EQ(fit_rigid_transform(source, target, {}, &fit), Status::ok);
  double worst_m = 0.0;
  for (int i = 0; i < 50; ++i) {
    const double error_m = (fit.apply(source[i]) - target[i]).norm();
    worst_m = error_m > worst_m ? error_m : worst_m;
  }
  FW_CHECK_LT(worst_m, 1e-9);
}

}  // namespace
}  // namespace hivecal
