#include <gtest/gtest.h>

#include <cstring>

#include "alloc_trap.hpp"
#include "hivecal/kinematics.hpp"
#include "hivecal/random.hpp"
#include "test_data.hpp"

namespace hivecal {
namespace {

TEST(Kinematics, Ur5ZeroPoseIsTheDatasheetPoint) {
  const RobotModel ur5 = nominal_model(RobotType::ur5);
  Vec3 p;
  EXPECT_NO_HEAP(p = fk_tool_point(ur5, JointVector::Zero()));
  EXPECT_NEAR(p.x(), -0.425 - 0.39225, 1e-15);
  EXPECT_NEAR(p.y(), -(0.10915 + 0.0823), 1e-15);
  EXPECT_NEAR(p.z(), 0.089159 - 0.09465, 1e-15);
}

TEST(Kinematics, ToolPointFastPathAgreesWithPoseChain) {
  Random random(11);
  for (RobotType type : {RobotType::ur3, RobotType::ur5, RobotType::ur10, RobotType::ur5e}) {
    RobotModel model = test::perturbed_model(nominal_model(type), &random, 1e-3, 1e-3);
    model.tool_m << 0.01, -0.02, 0.15;
    for (int i = 0; i < 200; ++i) {
      const JointVector q = test::random_joints(&random);
      RigidTransform flange;
      Vec3 fast;
      EXPECT_NO_HEAP(flange = fk_flange(model, q));
      EXPECT_NO_HEAP(fast = fk_tool_point(model, q));
      EXPECT_LT((flange.apply(model.tool_m) - fast).norm(), 1e-14);
      EXPECT_NEAR(flange.rotation.determinant(), 1.0, 1e-14);
    }
  }
}

// Property test: the analytic Jacobian equals central finite differences for random
// geometries and poses, for all 27 parameters.
TEST(Kinematics, JacobianMatchesCentralDifferences) {
  Random random(12);
  for (int trial = 0; trial < 300; ++trial) {
    RobotModel model = test::perturbed_model(nominal_model(RobotType::ur5), &random, 5e-3, 5e-3);
    model.tool_m << random.uniform(-0.05, 0.05), random.uniform(-0.05, 0.05), random.uniform(0.0, 0.2);
    const JointVector q = test::random_joints(&random);
    ToolPointJacobian jacobian;
    Vec3 point;
    EXPECT_NO_HEAP(point = tool_point_jacobian(model, q, &jacobian));
    EXPECT_LT((point - fk_tool_point(model, q)).norm(), 1e-14);
    const ModelParams params = to_params(model);
    for (int k = 0; k < kModelParamCount; ++k) {
      const double h = 1e-6;
      ModelParams plus = params;
      ModelParams minus = params;
      plus(k) += h;
      minus(k) -= h;
      const Vec3 numeric = (fk_tool_point(from_params(plus), q) - fk_tool_point(from_params(minus), q)) / (2 * h);
      EXPECT_LT((numeric - jacobian.col(k)).norm(), 1e-8) << "parameter " << k << " trial " << trial;
    }
  }
}

TEST(Kinematics, ParamsRoundTrip) {
  Random random(13);
  RobotModel model = test::perturbed_model(nominal_model(RobotType::ur10), &random, 1e-3, 1e-3);
  model.tool_m << 1.0, 2.0, 3.0;
  const RobotModel back = from_params(to_params(model));
  EXPECT_EQ(0, std::memcmp(&back, &model, sizeof model));
  EXPECT_EQ(to_params(model)(model_param_index(2, DhField::a)), model.joints[2].a_m);
  EXPECT_EQ(to_params(model)(tool_param_index(2)), 3.0);
}

TEST(Kinematics, RobotTypeNames) {
  RobotType type = RobotType::ur3;
  EXPECT_EQ(robot_type_from_name("ur10", &type), Status::ok);
  EXPECT_EQ(type, RobotType::ur10);
  EXPECT_EQ(robot_type_from_name("ur5e", &type), Status::ok);
  EXPECT_EQ(type, RobotType::ur5e);
  EXPECT_EQ(robot_type_from_name("ur7", &type), Status::invalid_argument);
  EXPECT_EQ(robot_type_from_name(nullptr, &type), Status::invalid_argument);
  EXPECT_STREQ(robot_type_name(RobotType::ur5), "ur5");
}

TEST(Kinematics, UrDeltasRoundTripAndRejectNaN) {
  Random random(14);
  const RobotModel nominal = nominal_model(RobotType::ur5e);
  const RobotModel calibrated = test::perturbed_model(nominal, &random, 1e-3, 1e-3);
  const UrCalibrationDeltas deltas = ur_deltas_between(nominal, calibrated);
  RobotModel rebuilt;
  EXPECT_EQ(apply_ur_deltas(nominal, deltas, &rebuilt), Status::ok);
  EXPECT_LT((to_params(rebuilt) - to_params(calibrated)).cwiseAbs().maxCoeff(), 1e-16);
  UrCalibrationDeltas bad = deltas;
  bad.delta_d_m[3] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(apply_ur_deltas(nominal, bad, &rebuilt), Status::non_finite_input);
}

}  // namespace
}  // namespace hivecal
