// Forward kinematics at known poses, FK paths agreeing, and the analytic Jacobian against
// central differences, on the MCU's FPU (or soft-float doubles on the M4).
#include <cstring>
#include <limits>

#include "harness.hpp"
#include "hivecal/kinematics.hpp"
#include "hivecal/random.hpp"
#include "test_data.hpp"

namespace hivecal {
namespace {

FW_TEST(Kinematics, Ur5ZeroPoseIsTheDatasheetPoint) {
  const Vec3 p = fk_tool_point(nominal_model(RobotType::ur5), JointVector::Zero());
  FW_CHECK_NEAR(p.x(), -0.425 - 0.39225, 1e-15);
  FW_CHECK_NEAR(p.y(), -(0.10915 + 0.0823), 1e-15);
  FW_CHECK_NEAR(p.z(), 0.089159 - 0.09465, 1e-15);
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
  Random random(11);
  for (RobotType type : {RobotType::ur3, RobotType::ur5, RobotType::ur10, RobotType::ur5e}) {
    RobotModel model = test::perturbed_model(nominal_model(type), &random, 1e-3, 1e-3);
    model.tool_m << 0.01, -0.02, 0.15;
    for (int i = 0; i < 20; ++i) {
      const JointVector q = test::random_joints(&random);
      const RigidTransform flange = fk_flange(model, q);
      const Vec3 fast = fk_tool_point(model, q);
      FW_CHECK_LT((flange.apply(model.tool_m) - fast).norm(), 1e-14);
      FW_CHECK_NEAR(flange.rotation.determinant(), 1.0, 1e-14);
    }
  }
}

FW_TEST(Kinematics, JacobianMatchesCentralDifferences) {
  Random random(12);
  for (int trial = 0; trial < 10; ++trial) {
    RobotModel model = test::perturbed_model(nominal_model(RobotType::ur5), &random, 5e-3, 5e-3);
    model.tool_m << random.uniform(-0.05, 0.05), random.uniform(-0.05, 0.05), random.uniform(0.0, 0.2);
    const JointVector q = test::random_joints(&random);
    ToolPointJacobian jacobian;
    const Vec3 point = tool_point_jacobian(model, q, &jacobian);
    FW_CHECK_LT((point - fk_tool_point(model, q)).norm(), 1e-14);
    const ModelParams params = to_params(model);
    double worst = 0.0;
    for (int k = 0; k < kModelParamCount; ++k) {
      const double h = 1e-6;
      ModelParams plus = params;
      ModelParams minus = params;
      plus(k) += h;
      minus(k) -= h;
      const Vec3 numeric = (fk_tool_point(from_params(plus), q) - fk_tool_point(from_params(minus), q)) / (2 * h);
      const double error = (numeric - jacobian.col(k)).norm();
      worst = error > worst ? error : worst;
    }
    FW_CHECK_LT(worst, 1e-8);
  }
}

FW_TEST(Kinematics, ParamsRoundTrip) {
  Random random(13);
  RobotModel model = test::perturbed_model(nominal_model(RobotType::ur10), &random, 1e-3, 1e-3);
  model.tool_m << 1.0, 2.0, 3.0;
  const RobotModel back = from_params(to_params(model));
  FW_CHECK_EQ(std::memcmp(&back, &model, sizeof model), 0);
  FW_CHECK_EQ(to_params(model)(model_param_index(2, DhField::a)), model.joints[2].a_m);
  FW_CHECK_EQ(to_params(model)(tool_param_index(2)), 3.0);
}

FW_TEST(Kinematics, RobotTypeNames) {
  RobotType type = RobotType::ur3;
  FW_CHECK_EQ(robot_type_from_name("ur10", &type), Status::ok);
  FW_CHECK_EQ(type, RobotType::ur10);
  FW_CHECK_EQ(robot_type_from_name("ur7", &type), Status::invalid_argument);
  FW_CHECK_EQ(robot_type_from_name(nullptr, &type), Status::invalid_argument);
  FW_CHECK_EQ(std::strcmp(robot_type_name(RobotType::ur5e), "ur5e"), 0);
}

FW_TEST(Kinematics, UrDeltasRoundTripAndRejectNaN) {
  Random random(14);
  const RobotModel nominal = nominal_model(RobotType::ur5e);
  const RobotModel calibrated = test::perturbed_model(nominal, &random, 1e-3, 1e-3);
  const UrCalibrationDeltas deltas = ur_deltas_between(nominal, calibrated);
  RobotModel rebuilt;
  FW_CHECK_EQ(apply_ur_deltas(nominal, deltas, &rebuilt), Status::ok);
  FW_CHECK_LT((to_params(rebuilt) - to_params(calibrated)).cwiseAbs().maxCoeff(), 1e-16);
  UrCalibrationDeltas bad = deltas;
  bad.delta_d_m[3] = std::numeric_limits<double>::quiet_NaN();
  FW_CHECK_EQ(apply_ur_deltas(nominal, bad, &rebuilt), Status::non_finite_input);
}

}  // namespace
}  // namespace hivecal
