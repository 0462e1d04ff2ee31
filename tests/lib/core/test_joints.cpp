// The joints (core/joints.hpp): the build's joint capacity and the joint types, usable at compile
// time, free of Eigen (checked by including the header first), and the size every joint-indexed
// type of the library uses.
#include "hivecal/core/joints.hpp"  // first, alone: it must not need or bring in Eigen

#if defined(EIGEN_CORE_H) || defined(EIGEN_WORLD_VERSION)
constexpr bool kJointsHeaderPullsEigen = true;
#else
constexpr bool kJointsHeaderPullsEigen = false;
#endif

#include <gtest/gtest.h>

#include <type_traits>

#include "hivecal/core/types.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/wire/records.hpp"

namespace hivecal::joints_test {
namespace {

// Constant expressions: arrays can be sized with them.
constexpr int kArrayOfJoints[kMaxJoints] = {};
static_assert(sizeof kArrayOfJoints / sizeof kArrayOfJoints[0] == kMaxJoints, "kMaxJoints is a constant expression");

TEST(Joints, TheCapacityHoldsTheSixAxesOfTheBuiltInArms) {
  EXPECT_EQ(kSixJoints, 6);
  EXPECT_GE(kMaxJoints, kSixJoints);
  EXPECT_TRUE((std::is_same<decltype(kMaxJoints), const int>::value));
}

TEST(Joints, HeaderDoesNotBringInEigen) {
  EXPECT_FALSE(kJointsHeaderPullsEigen);
}

TEST(Joints, SizesTheJointVectorTheWireRecordAndTheModel) {
  EXPECT_EQ(JointVector::RowsAtCompileTime, kMaxJoints);
  EXPECT_EQ(JointVector::ColsAtCompileTime, 1);
  const JointStateRecord record;
  EXPECT_EQ(record.joint_count, kSixJoints);
  EXPECT_EQ(sizeof record.q_rad / sizeof record.q_rad[0], static_cast<std::size_t>(kMaxJoints));
  EXPECT_EQ(sizeof record.qd_rad_s / sizeof record.qd_rad_s[0], static_cast<std::size_t>(kMaxJoints));
  EXPECT_EQ(sizeof record.current_a / sizeof record.current_a[0], static_cast<std::size_t>(kMaxJoints));
  const RobotModel model;
  EXPECT_EQ(sizeof model.joints / sizeof model.joints[0], static_cast<std::size_t>(kMaxJoints));
  EXPECT_EQ(model.joint_count, kSixJoints);
  EXPECT_TRUE(all_revolute(model));
}

TEST(Joints, AJointVectorStartsAtZeroAndTakesFewerReadingsThanItHolds) {
  const JointVector zero;
  EXPECT_TRUE(zero.isZero());
  constexpr double kReadings[kSixJoints] = {0.1, -0.2, 0.3, -0.4, 0.5, -0.6};
  const JointVector q = joint_vector(kReadings);
  JointVector r = JointVector::Constant(9.0);
  r << 0.1, -0.2, 0.3, -0.4, 0.5, -0.6;  // the joints after the last given are 0, whatever they were
  for (int j = 0; j < kSixJoints; ++j) {
    EXPECT_EQ(q(j), kReadings[j]) << j;
    EXPECT_EQ(r(j), kReadings[j]) << j;
  }
  for (int j = kSixJoints; j < kMaxJoints; ++j) {
    EXPECT_EQ(q(j), 0.0) << j;
    EXPECT_EQ(r(j), 0.0) << j;
  }
}

TEST(Joints, EachJointHasItsType) {
  RobotModel model;
  model.joint_count = 3;
  set_joint_type(&model, 0, JointType::prismatic);
  EXPECT_EQ(joint_type(model, 0), JointType::prismatic);
  EXPECT_EQ(joint_type(model, 1), JointType::revolute);
  EXPECT_FALSE(all_revolute(model));
  EXPECT_EQ(check_joint_layout(model), Status::ok);
  set_joint_type(&model, 0, JointType::revolute);
  EXPECT_TRUE(all_revolute(model));
  set_joint_type(&model, 3, JointType::prismatic);  // beyond its joints
  EXPECT_EQ(check_joint_layout(model), Status::invalid_argument);
  model.prismatic_joints = 0;
  model.joints[4].a_m = 0.1;  // an unused joint with geometry
  EXPECT_EQ(check_joint_layout(model), Status::invalid_argument);
  model.joints[4].a_m = 0.0;
  for (int count : {0, kMaxJoints + 1}) {
    model.joint_count = count;
    EXPECT_EQ(check_joint_layout(model), Status::invalid_argument) << count;
  }
}

}  // namespace
}  // namespace hivecal::joints_test
