// Rigid fit (Kabsch) checks run by both tests/lib/model/test_rigid_fit.cpp and the firmware image
// (tests/firmware/test_rigid_fit.cpp): exact recovery, reflection guard, weights, the specific
// error of each degenerate input, accuracy far from the origin.
#pragma once

#include <cstddef>
#include <limits>

#include "hivecal/core/random.hpp"
#include "hivecal/model/rigid_fit.hpp"
#include "testkit/check_log.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::test {

/// A transform of a random rotation and the given translation [m].
inline RigidTransform with_random_rotation(Random* random, const Vec3& translation_m) {
  RigidTransform transform;
  transform.rotation = random_rotation(random);
  transform.translation_m = translation_m;
  return transform;
}

/// `trials` random transforms of 3..19 exact pairs each are recovered to 1e-12.
inline CheckLog rigid_fit_recovers_random_transforms(int trials) {
  CheckLog log;
  Random random(21);
  for (int trial = 0; trial < trials; ++trial) {
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
    const Status status = fit_rigid_transform(Span<const Vec3>(source, n), Span<const Vec3>(target, n), {}, &fit);
    if (!log.status(status, Status::ok, "fit status")) return log;
    log.less((fit.rotation - truth.rotation).norm(), 1e-12, "rotation error");
    log.less((fit.translation_m - truth.translation_m).norm(), 1e-12, "translation error [m]");
    log.near(fit.rotation.determinant(), 1.0, 1e-12, "det(rotation)");
  }
  return log;
}

/// A mirror-image target gets the best proper rotation, never det = -1.
inline CheckLog rigid_fit_never_returns_a_reflection() {
  CheckLog log;
  Vec3 source[4] = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  Vec3 target[4];
  for (int i = 0; i < 4; ++i) target[i] = Vec3(source[i].x(), source[i].y(), -source[i].z());
  RigidTransform fit;
  if (!log.status(fit_rigid_transform(source, target, {}, &fit), Status::ok, "fit status")) return log;
  log.near(fit.rotation.determinant(), 1.0, 1e-12, "det(rotation)");
  return log;
}

/// A zero weight removes an outlier's pull; without weights it pulls.
inline CheckLog rigid_fit_weights_select_the_pairs_that_count() {
  CheckLog log;
  Random random(22);
  const RigidTransform truth = with_random_rotation(&random, Vec3(1, 2, 3));
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
  if (!log.status(fit_rigid_transform(source, target, weights, &fit), Status::ok, "weighted fit")) return log;
  log.less((fit.translation_m - truth.translation_m).norm(), 1e-12, "weighted translation error [m]");
  if (!log.status(fit_rigid_transform(source, target, {}, &fit), Status::ok, "unweighted fit")) return log;
  log.greater((fit.translation_m - truth.translation_m).norm(), 1e-3, "unweighted translation error [m]");
  return log;
}

/// Each degenerate input gets its own error.
inline CheckLog rigid_fit_degenerate_inputs_get_specific_errors() {
  CheckLog log;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  RigidTransform fit;
  Vec3 two[2] = {Vec3(0, 0, 0), Vec3(1, 0, 0)};
  log.status(fit_rigid_transform(two, two, {}, &fit), Status::too_few_samples, "two pairs");
  Vec3 collinear[5] = {Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(2, 2, 2), Vec3(3, 3, 3), Vec3(-1, -1, -1)};
  log.status(fit_rigid_transform(collinear, collinear, {}, &fit), Status::degenerate_geometry, "collinear");
  Vec3 same[4] = {Vec3(1, 2, 3), Vec3(1, 2, 3), Vec3(1, 2, 3), Vec3(1, 2, 3)};
  log.status(fit_rigid_transform(same, same, {}, &fit), Status::degenerate_geometry, "one point four times");
  Vec3 with_nan[3] = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, nan, 0)};
  log.status(fit_rigid_transform(with_nan, with_nan, {}, &fit), Status::non_finite_input, "NaN coordinate");
  Vec3 with_inf[3] = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, inf, 0)};
  log.status(fit_rigid_transform(with_inf, with_inf, {}, &fit), Status::non_finite_input, "Inf coordinate");
  Vec3 good[3] = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  double negative[3] = {1.0, -1.0, 1.0};
  log.status(fit_rigid_transform(good, good, negative, &fit), Status::invalid_argument, "negative weight");
  double short_weights[2] = {1.0, 1.0};
  log.status(fit_rigid_transform(good, good, short_weights, &fit), Status::invalid_argument, "short weights");
  log.status(fit_rigid_transform(good, Span<const Vec3>(good, 2), {}, &fit), Status::invalid_argument, "short target");
  log.status(fit_rigid_transform(good, good, {}, &fit), Status::ok, "three good pairs");
  return log;
}

/// Tracker coordinates kilometres from the origin: sums are kept relative to the first pair,
/// so every point still maps within 1 nm.
inline CheckLog rigid_fit_far_from_origin_stays_accurate() {
  CheckLog log;
  Random random(23);
  const RigidTransform truth = with_random_rotation(&random, Vec3(3000.0, -2000.0, 1000.0));
  Vec3 source[50];
  Vec3 target[50];
  for (int i = 0; i < 50; ++i) {
    source[i] =
        Vec3(1000.0, 1000.0, 1000.0) + Vec3(random.uniform(-1, 1), random.uniform(-1, 1), random.uniform(-1, 1));
    target[i] = truth.apply(source[i]);
  }
  RigidTransform fit;
  if (!log.status(fit_rigid_transform(source, target, {}, &fit), Status::ok, "fit status")) return log;
  for (int i = 0; i < 50; ++i) log.less((fit.apply(source[i]) - target[i]).norm(), 1e-9, "point error [m]");
  return log;
}

}  // namespace hivecal::test
