// Forward kinematics at known poses, FK paths agreeing, and the analytic Jacobian against
// central differences, on the MCU's FPU (or soft-float doubles on the M4). The shared checks
// are tests/testkit/kinematics_checks.hpp (the host suite runs them with more poses).
#include "harness.hpp"
#include "hivecal/model/kinematics.hpp"
#include "testkit/kinematics_checks.hpp"

namespace hivecal {
namespace {

FW_TEST(Kinematics, Ur5ZeroPoseIsTheDatasheetPoint) {
  FW_CHECK_LOG(test::ur5_zero_pose_is_the_datasheet_point());
}

FW_TEST(Kinematics, Ur5ElbowUpPoseIsTheDatasheetPoint) {
  // q2 = -pi/2 raises upper arm and forearm straight up: z = d1 + |a2| + |a3|, and the wrist
  // offsets d5 (now along -x) and d4 + d6 (along -y) stay horizontal.
  JointVector q = JointVector::Zero();
  q(1) = -math::kHalfPi;
  const Vec3 p = fk_tool_point(nominal_model(RobotType::ur5), q);
  FW_CHECK_NEAR(p.x(), -0.09465, 1e-15);
  FW_CHECK_NEAR(p.y(), -(0.10915 + 0.0823), 1e-15);
  FW_CHECK_NEAR(p.z(), 0.089159 + 0.425 + 0.39225, 1e-15);
}

FW_TEST(Kinematics, ToolPointFastPathAgreesWithPoseChain) {
  FW_CHECK_LOG(test::tool_point_fast_path_agrees_with_pose_chain(20));
}

FW_TEST(Kinematics, JacobianMatchesCentralDifferences) {
  FW_CHECK_LOG(test::jacobian_matches_central_differences(10));
}

FW_TEST(Kinematics, ParamsRoundTrip) {
  FW_CHECK_LOG(test::params_round_trip());
}

FW_TEST(Kinematics, RobotTypeNames) {
  FW_CHECK_LOG(test::robot_type_names());
}

FW_TEST(Kinematics, UrDeltasRoundTripAndRejectNaN) {
  FW_CHECK_LOG(test::ur_deltas_round_trip_and_reject_nan());
}

}  // namespace
}  // namespace hivecal
