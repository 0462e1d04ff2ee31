// Kinematics: the checks are tests/testkit/kinematics_checks.hpp, shared with the firmware
// image; here with more random poses and under the allocation trap.
#include <gtest/gtest.h>

#include "testkit/alloc_trap.hpp"
#include "testkit/check_log_gtest.hpp"
#include "testkit/kinematics_checks.hpp"

namespace hivecal::kinematics_test {
namespace {

TEST(Kinematics, Ur5ZeroPoseIsTheDatasheetPoint) {
  test::CheckLog log;
  EXPECT_NO_HEAP(log = test::ur5_zero_pose_is_the_datasheet_point());
  EXPECT_CHECKS(log);
}

TEST(Kinematics, ToolPointFastPathAgreesWithPoseChain) {
  test::CheckLog log;
  EXPECT_NO_HEAP(log = test::tool_point_fast_path_agrees_with_pose_chain(200));
  EXPECT_CHECKS(log);
}

TEST(Kinematics, JacobianMatchesCentralDifferences) {
  test::CheckLog log;
  EXPECT_NO_HEAP(log = test::jacobian_matches_central_differences(300));
  EXPECT_CHECKS(log);
}

TEST(Kinematics, ParamsRoundTrip) {
  EXPECT_CHECKS(test::params_round_trip());
}

TEST(Kinematics, RobotTypeNames) {
  EXPECT_CHECKS(test::robot_type_names());
}

TEST(Kinematics, UrDeltasRoundTripAndRejectNaN) {
  EXPECT_CHECKS(test::ur_deltas_round_trip_and_reject_nan());
}

}  // namespace
}  // namespace hivecal::kinematics_test
