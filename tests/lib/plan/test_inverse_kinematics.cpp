// Inverse kinematics of a flange pose (plan/inverse_kinematics.hpp): rotation vectors that
// round-trip at every angle (a half turn included), poses of random joints found again within
// the tolerances and the limits, an unreachable pose refused, no heap.
#include <gtest/gtest.h>

#include <cmath>

#include "hivecal/core/math.hpp"
#include "hivecal/model/full_params.hpp"
#include "hivecal/plan/inverse_kinematics.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/other_arms.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::inverse_kinematics_test {
namespace {

TEST(InverseKinematics, RotationVectorsRoundTripAtEveryAngle) {
  Random random(7);
  for (double angle : {0.0, 1e-12, 1e-7, 0.3, 1.5, 3.0, math::kPi - 1e-7, math::kPi}) {
    for (int k = 0; k < 20; ++k) {
      Vec3 axis(random.normal(), random.normal(), random.normal());
      axis.normalize();
      const Mat3 r = rotation_from_vector(angle * axis);
      const Vec3 v = rotation_vector_of(r);
      EXPECT_LE(v.norm(), math::kPi + 1e-12);
      // The same rotation (at a half turn, the axis may come out reversed: the same turn).
      EXPECT_LT((rotation_from_vector(v) - r).norm(), 1e-9) << angle;
      if (angle < 3.0) {
        EXPECT_LT((v - angle * axis).norm(), 1e-9) << angle;
      }
    }
  }
}

/// Solves for `target` with starts seeded by `seed` and checks the joints reach it within the
/// tolerances and `limits`, nothing beyond the model's joints.
void expect_reached(const RobotModel& model, const JointLimits& limits, const RigidTransform& target,
                    std::uint64_t seed) {
  Random starts(seed);
  JointVector q;
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = solve_flange_pose(model, limits, target, InverseKinematicsOptions{}, &starts, &q));
  ASSERT_EQ(status, Status::ok) << seed;
  const RigidTransform reached = fk_flange(model, q);
  EXPECT_LT((reached.translation_m - target.translation_m).norm(), 1e-6) << seed;
  EXPECT_LT(rotation_vector_of(target.rotation * reached.rotation.transpose()).norm(), 1e-6) << seed;
  for (int j = 0; j < model.joint_count; ++j) {
    EXPECT_GE(q(j), limits.lower_rad(j));
    EXPECT_LE(q(j), limits.upper_rad(j));
  }
  for (int j = model.joint_count; j < kMaxJoints; ++j) EXPECT_EQ(q(j), 0.0);
}

TEST(InverseKinematics, PosesOfRandomJointsAreReachedWithinTheLimits) {
  Random draws(11);
  const JointLimits limits = default_joint_limits(RobotType::ur5);
  for (int trial = 0; trial < 40; ++trial) {
    const RobotModel model = test::perturbed_model(nominal_model(RobotType::ur5), &draws, 1e-3, 1e-3);
    JointVector q_true;
    for (int j = 0; j < kSixJoints; ++j) q_true(j) = draws.uniform(-3.0, 3.0);
    expect_reached(model, limits, fk_flange(model, q_true), 100 + static_cast<std::uint64_t>(trial));
  }
}

TEST(InverseKinematics, AnUnreachablePoseAndBadArgumentsAreRefused) {
  const RobotModel model = nominal_model(RobotType::ur5);
  const JointLimits limits = default_joint_limits(RobotType::ur5);
  Random random(3);
  JointVector q = JointVector::Zero();
  RigidTransform far = fk_flange(model, q);
  far.translation_m += Vec3(3.0, 0.0, 0.0);  // beyond the UR5's 0.85 m reach
  EXPECT_EQ(solve_flange_pose(model, limits, far, InverseKinematicsOptions{}, &random, &q), Status::not_converged);
  RigidTransform nan_target = fk_flange(model, JointVector::Zero());
  nan_target.translation_m.x() = std::nan("");
  EXPECT_EQ(solve_flange_pose(model, limits, nan_target, InverseKinematicsOptions{}, &random, &q),
            Status::non_finite_input);
  InverseKinematicsOptions no_starts;
  no_starts.starts = 0;
  EXPECT_EQ(solve_flange_pose(model, limits, far, no_starts, &random, &q), Status::invalid_argument);
  EXPECT_EQ(solve_flange_pose(model, limits, far, InverseKinematicsOptions{}, nullptr, &q), Status::invalid_argument);
}

// A seven-joint arm has a continuum of joints for a pose: any one within the limits will do.
TEST(InverseKinematics, ARedundantArmReachesPosesWithinItsLimits) {
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of six joints";
  Random draws(12);
  const RobotModel model = test::many_joint_arm_model(test::ManyJointArm::iiwa14);
  JointLimits limits;
  const double limit_rad[7] = {2.96, 2.09, 2.96, 2.09, 2.96, 2.09, 3.05};  // the iiwa 14's
  for (int j = 0; j < 7; ++j) {
    limits.lower_rad(j) = -limit_rad[j];
    limits.upper_rad(j) = limit_rad[j];
  }
  for (int trial = 0; trial < 20; ++trial) {
    const JointVector q_true = test::many_joint_arm_joints(test::ManyJointArm::iiwa14, &draws);
    expect_reached(model, limits, fk_flange(model, q_true), 200 + static_cast<std::uint64_t>(trial));
  }
}

}  // namespace
}  // namespace hivecal::inverse_kinematics_test
