// The joint count (core/joints.hpp): six joints, usable at compile time, free of Eigen (checked
// by including the header first), and the size every joint-indexed type of the library uses.
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

// A constant expression: arrays can be sized with it.
constexpr int kArrayOfJoints[kJointCount] = {};
static_assert(sizeof kArrayOfJoints / sizeof kArrayOfJoints[0] == 6, "kJointCount is a constant expression");

TEST(Joints, CountsTheSixAxesOfTheModelledArms) {
  EXPECT_EQ(kJointCount, 6);
  EXPECT_TRUE((std::is_same<decltype(kJointCount), const int>::value));
}

TEST(Joints, HeaderDoesNotBringInEigen) {
  EXPECT_FALSE(kJointsHeaderPullsEigen);
}

TEST(Joints, SizesTheJointVectorTheWireRecordAndTheModel) {
  EXPECT_EQ(JointVector::RowsAtCompileTime, kJointCount);
  EXPECT_EQ(JointVector::ColsAtCompileTime, 1);
  const JointStateRecord record;
  EXPECT_EQ(sizeof record.q_rad / sizeof record.q_rad[0], 6u);
  EXPECT_EQ(sizeof record.qd_rad_s / sizeof record.qd_rad_s[0], 6u);
  EXPECT_EQ(sizeof record.current_a / sizeof record.current_a[0], 6u);
  const RobotModel model;
  EXPECT_EQ(sizeof model.joints / sizeof model.joints[0], 6u);
}

}  // namespace
}  // namespace hivecal::joints_test
