// Deterministic synthetic robot/tracker data for tests (own PRNG: same on every target).
#pragma once

#include <cmath>

#include "hivecal/model/dataset.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/core/random.hpp"

namespace hivecal::test {

/// A geometry perturbed from `nominal` by Gaussian errors of the given sizes [m], [rad].
inline RobotModel perturbed_model(const RobotModel& nominal, Random* random, double length_sigma_m,
                                  double angle_sigma_rad) {
  RobotModel model = nominal;
  for (DhJoint& joint : model_joints(&model)) {
    joint.theta_offset_rad += angle_sigma_rad * random->normal();
    joint.d_m += length_sigma_m * random->normal();
    joint.a_m += length_sigma_m * random->normal();
    joint.alpha_rad += angle_sigma_rad * random->normal();
  }
  return model;
}

/// A random proper rotation: axis-angle with the library's own trig (Rodrigues' formula).
inline Mat3 random_rotation(Random* random) {
  Vec3 axis;
  axis << random->normal(), random->normal(), random->normal();  // defined order (not constructor arguments)
  axis.normalize();
  const double angle = random->uniform(-3.1, 3.1);
  Mat3 k;
  k << 0, -axis.z(), axis.y(), axis.z(), 0, -axis.x(), -axis.y(), axis.x(), 0;
  return Mat3::Identity() + math::sin(angle) * k + (1.0 - math::cos(angle)) * k * k;
}

/// Joint positions spread over a UR's useful workspace [rad].
inline JointVector random_joints(Random* random) {
  JointVector q;
  q << random->uniform(-3.0, 3.0), random->uniform(-2.6, -0.5), random->uniform(-2.4, 2.4), random->uniform(-3.0, 0.0),
      random->uniform(-2.8, -0.3), random->uniform(-3.0, 3.0);
  return q;
}

/// A tracker placement: some rotation about z and tilt, ~3 m away.
inline RigidTransform example_base_to_tracker() {
  RigidTransform t;
  const double yaw = 0.7;
  const double tilt = 0.05;
  Mat3 rz;
  rz << math::cos(yaw), -math::sin(yaw), 0.0, math::sin(yaw), math::cos(yaw), 0.0, 0.0, 0.0, 1.0;
  Mat3 rx;
  rx << 1.0, 0.0, 0.0, 0.0, math::cos(tilt), -math::sin(tilt), 0.0, math::sin(tilt), math::cos(tilt);
  t.rotation = rz * rx;
  t.translation_m << 2.5, -1.2, 0.4;
  return t;
}

/// Fills `dataset` with `count` samples of `truth` seen by a tracker at `base_to_tracker`
/// with isotropic Gaussian noise `noise_m`.
inline void fill_dataset(const RobotModel& truth, const RigidTransform& base_to_tracker, std::size_t count,
                         double noise_m, Random* random, DatasetBase* dataset) {
  for (std::size_t i = 0; i < count; ++i) {
    const JointVector q = random_joints(random);
    Vec3 noise;
    noise << random->normal(), random->normal(), random->normal();
    (void)dataset->add(q, base_to_tracker.apply(fk_tool_point(truth, q)) + noise_m * noise);
  }
}

/// fill_dataset with 10 um noise and an effect no rigid model holds, as a real arm's unmodelled
/// deflections: up to 3 mm, smooth in the joints (the same draws as fill_dataset).
inline void fill_with_unmodelled_effect(const RobotModel& truth, const RigidTransform& base_to_tracker,
                                        std::size_t count, Random* random, DatasetBase* dataset) {
  for (std::size_t i = 0; i < count; ++i) {
    const JointVector q = random_joints(random);
    Vec3 noise;
    noise << random->normal(), random->normal(), random->normal();
    const Vec3 effect_m =
        3e-3 * Vec3(std::sin(3.0 * q(0) + 2.0 * q(1)), std::cos(4.0 * q(2) - q(4)), std::sin(5.0 * q(3)));
    (void)dataset->add(q, base_to_tracker.apply(fk_tool_point(truth, q)) + 10e-6 * noise + effect_m);
  }
}

}  // namespace hivecal::test
