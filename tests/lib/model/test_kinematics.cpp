// Kinematics: the checks are tests/testkit/kinematics_checks.hpp, shared with the firmware
// image; here with more random poses and under the allocation trap.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "hivecal/model/dh_convention.hpp"
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

TEST(Kinematics, EveryBuiltinNameRoundTripsAndIsListed) {
  std::string listed;
  for (const RobotType type : builtin_robot_types()) {
    const char* name = robot_type_name(type);
    RobotType parsed = RobotType::ur5;
    EXPECT_EQ(robot_type_from_name(name, &parsed), Status::ok) << name;
    EXPECT_EQ(parsed, type) << name;
    listed += (listed.empty() ? "" : ", ") + std::string(name);
  }
  EXPECT_EQ(listed, robot_type_names());  // the message's list is the types, in their order
  EXPECT_EQ(builtin_robot_types().size(), kMaxJoints >= 7 ? 12U : 7U);
  RobotType type = RobotType::ur5;
  EXPECT_EQ(robot_type_from_name("iiwa", &type), Status::invalid_argument);
  EXPECT_EQ(robot_type_from_name("IIWA14", &type), Status::invalid_argument);  // names are lower case
  EXPECT_EQ(type, RobotType::ur5);
}

#if HIVECAL_MAX_JOINTS >= 7

/// The flange of `type`'s nominal model at q in the maker's own base frame (nominal_convention's
/// base offset in front of the chain).
RigidTransform maker_flange(RobotType type, const JointVector& q_rad) {
  ModifiedDhBase base;
  const DhConvention convention = nominal_convention(type, &base);
  const RobotModel model = nominal_model(type);
  const RigidTransform chain = fk_flange(model, q_rad);
  return convention == DhConvention::modified ? base.transform().then_after(chain) : chain;
}

/// JointVector of seven joint readings [rad] (the rest zero).
JointVector seven(double q1, double q2, double q3, double q4, double q5, double q6, double q7) {
  JointVector q = JointVector::Zero();
  q.head<7>() << q1, q2, q3, q4, q5, q6, q7;
  return q;
}

void expect_flange(RobotType type, const JointVector& q, const Vec3& point_m, const Mat3& rotation,
                   double tolerance_m) {
  RigidTransform flange;
  EXPECT_NO_HEAP(flange = maker_flange(type, q));
  EXPECT_LT((flange.translation_m - point_m).norm(), tolerance_m)
      << robot_type_name(type) << ": " << flange.translation_m.x() << ", " << flange.translation_m.y() << ", "
      << flange.translation_m.z();
  EXPECT_LT((flange.rotation - rotation).cwiseAbs().maxCoeff(), 1e-12) << robot_type_name(type);
}

TEST(Kinematics, SevenAxisArmsReachTheirMakersReferencePoints) {
  constexpr double h = math::kHalfPi;
  const Mat3 identity = Mat3::Identity();
  const Mat3 down = Vec3(1.0, -1.0, -1.0).asDiagonal();  // flange z pointing down, x along the base's
  // KUKA iiwa 14 R820 straight up: 0.36 + 0.42 + 0.40 + 0.126 m; A2 at +90 deg lays it along +x.
  expect_flange(RobotType::iiwa14, JointVector::Zero(), Vec3(0.0, 0.0, 1.306), identity, 1e-12);
  Mat3 laid;
  laid << 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, -1.0, 0.0, 0.0;
  expect_flange(RobotType::iiwa14, seven(0.0, h, 0.0, 0.0, 0.0, 0.0, 0.0), Vec3(0.946, 0.0, 0.36), laid, 1e-12);
  // Franka at q = 0 from its published table: x a7 = 0.088, z d1 + d3 + d5 - flange = 0.926,
  // the flange facing down; at the "ready" pose of Franka's examples (0, -pi/4, 0, -3pi/4, 0,
  // pi/2, pi/4), 0.307 m ahead at 0.590 m (computed by hand from the published table: the
  // joints' senses, not only their lengths).
  for (const RobotType franka : {RobotType::panda, RobotType::fr3}) {
    expect_flange(franka, JointVector::Zero(), Vec3(0.088, 0.0, 0.926), down, 1e-12);
  }
  const double s = 0.5 * std::sqrt(2.0);
  Mat3 ready;
  ready << s, -s, 0.0, -s, -s, 0.0, 0.0, 0.0, -1.0;
  expect_flange(RobotType::panda, seven(0.0, -0.5 * h, 0.0, -1.5 * h, 0.0, h, 0.5 * h), Vec3(0.30689, 0.0, 0.59028),
                ready, 2e-5);
  // Kinova Gen3 at zero in Kinova's base (z up): the guide's 1.1873 m high, its wrist offsets
  // 0.0118 + 0.0128 m along -y; Kinova's URDF puts the interface at (0, -0.02485, 1.187255) m.
  expect_flange(RobotType::gen3, JointVector::Zero(), Vec3(0.0, -0.0246, 1.1873), identity, 1e-12);
  expect_flange(RobotType::gen3, JointVector::Zero(), Vec3(0.0, -0.02485, 1.187255), identity, 3e-4);
  // Barrett WAM at zero: straight up, 0.55 + 0.3 + 0.06 m (a3 and a4 cancel).
  expect_flange(RobotType::wam, JointVector::Zero(), Vec3(0.0, 0.0, 0.91), identity, 1e-12);
}

TEST(Kinematics, SevenAxisArmsHaveSevenRevoluteJointsAndTheirMakersLimits) {
  struct Expected {
    RobotType type;
    double lower_rad[7];
    double upper_rad[7];
  };
  constexpr double kDeg = math::kRadPerDeg;
  constexpr double kTurn = 2.0 * math::kPi;
  const Expected expected[] = {
      {RobotType::iiwa14,
       {-170 * kDeg, -120 * kDeg, -170 * kDeg, -120 * kDeg, -170 * kDeg, -120 * kDeg, -175 * kDeg},
       {170 * kDeg, 120 * kDeg, 170 * kDeg, 120 * kDeg, 170 * kDeg, 120 * kDeg, 175 * kDeg}},
      {RobotType::panda,
       {-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973},
       {2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973}},
      {RobotType::fr3,
       {-2.7437, -1.7837, -2.9007, -3.0421, -2.8065, 0.5445, -3.0159},
       {2.7437, 1.7837, 2.9007, -0.1518, 2.8065, 4.5169, 3.0159}},
      {RobotType::gen3,
       {-kTurn, -2.41, -kTurn, -2.66, -kTurn, -2.23, -kTurn},
       {kTurn, 2.41, kTurn, 2.66, kTurn, 2.23, kTurn}},
      {RobotType::wam, {-2.6, -2.0, -2.8, -0.9, -4.76, -1.6, -3.0}, {2.6, 2.0, 2.8, 3.1, 1.24, 1.6, 3.0}},
  };
  for (const Expected& arm : expected) {
    RobotModel model;
    JointVector lower = JointVector::Zero();
    JointVector upper = JointVector::Zero();
    Status status = Status::invalid_argument;
    EXPECT_NO_HEAP({
      model = nominal_model(arm.type);
      status = maker_joint_limits(arm.type, &lower, &upper);
    });
    EXPECT_EQ(model.joint_count, 7) << robot_type_name(arm.type);
    EXPECT_TRUE(all_revolute(model)) << robot_type_name(arm.type);
    EXPECT_EQ(model.tool_m, Vec3::Zero());  // at the maker's flange
    EXPECT_EQ(check_joint_layout(model), Status::ok);
    ASSERT_EQ(status, Status::ok) << robot_type_name(arm.type);
    for (int j = 0; j < 7; ++j) {
      EXPECT_EQ(lower(j), arm.lower_rad[j]) << robot_type_name(arm.type) << " joint " << j + 1;
      EXPECT_EQ(upper(j), arm.upper_rad[j]) << robot_type_name(arm.type) << " joint " << j + 1;
    }
    for (int j = 7; j < kMaxJoints; ++j) EXPECT_EQ(upper(j), kTurn);  // beyond the arm: unlimited
  }
  JointVector lower;
  JointVector upper;
  EXPECT_EQ(maker_joint_limits(RobotType::ur5, &lower, &upper), Status::invalid_argument);  // UR's turn +-360 deg
}

#endif

}  // namespace
}  // namespace hivecal::kinematics_test
